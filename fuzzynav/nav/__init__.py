"""Navigation maths: WGS-84 earth, attitude, strapdown mechanization, error models.

See :mod:`fuzzynav.nav.attitude` for the frame and angle conventions used throughout.
"""
