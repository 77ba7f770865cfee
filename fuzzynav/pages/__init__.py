"""The docs results pages, regenerated from the package: ``fuzzynav docs regenerate PAGE``.

:mod:`fuzzynav.pages.page_registry` maps a page name to its generator, its docs file and its
marked section; :mod:`fuzzynav.pages.common` holds what every generator shares (the
machine line, rewriting a marked section atomically).  The generator of a paper's page is
``fuzzynav.papers.paperNNN.page``; the cross-paper pages are modules of this package.
"""
