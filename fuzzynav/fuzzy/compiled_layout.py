"""Index constants of the compiled array form (shared by the builder and the kernels).

``iparams`` starts with a header of :data:`HEADER` int64 slots; the slots below name
them.  Offsets (``OFF_*``) point into ``iparams``, ``F_*`` into ``fparams`` and ``W_*``
into the caller's ``work`` buffer.  The tables they point to are

=============  =======================================================================
OFF_INVAR      per input: first input-term index, number of terms
OFF_OUTVAR     per output: first output-term index, number of terms, output kind,
               envelope capacity (points)
OFF_INTERM     per input term: membership code, parameter offset in fparams
OFF_OUTTERM    per output term: membership code, parameter offset in fparams
OFF_RULE       per rule: connective (0 and, 1 or), first antecedent, n antecedents
OFF_ANTE       per antecedent: input index, input-term index, negated (0/1)
OFF_OUTPTR     per output, CSR pointer (n_outputs + 1 entries) into the consequents
OFF_CONS       per consequent: rule index, output-term index
F_INRANGE      per input: lo, hi
F_OUTRANGE     per output: lo, hi
F_DEFAULT      per output: value held when no rule fires
F_WEIGHT       per rule: weight
F_GL           Gauss-Legendre tables on [0, 1] for n = 1..NGL (pairs node, weight;
               table n starts at F_GL + n (n - 1))
=============  =======================================================================

Never renumber; the tag changes if the layout ever does.
"""

__all__ = ["TAG_VALUE", "HEADER", "PIECE_VERTS", "PIECE_STRIDE", "MAX_RTOL", "GAP_RTOL", "CODES"]
TAG_VALUE = 0x46555A31  # "FUZ1"
HEADER = 48

(TAG, N_IN, N_OUT, N_RULES, KIND, OP_AND, OP_OR, OP_IMP, OP_AGG, OP_DEFUZZ, WORK_SIZE,
 OFF_INVAR, OFF_OUTVAR, OFF_INTERM, OFF_OUTTERM, OFF_RULE, OFF_ANTE, OFF_OUTPTR, OFF_CONS,
 N_INTERM, N_OUTTERM, MERGE_BY_TERM, F_INRANGE, F_OUTRANGE, F_DEFAULT, F_WEIGHT, F_GL, NGL,
 W_X, W_MU, W_FIRE, W_LEVEL, W_PIECE, W_ENV, W_SCRATCH, PIECE_MAX, ENV_CAP) = range(37)

# system kinds, operators (codes are part of the format)
MAMDANI, SUGENO = 0, 1
AND_MIN, AND_PROD = 0, 1
OR_MAX, OR_PROBOR = 0, 1
IMP_MIN, IMP_PROD = 0, 1
AGG_MAX, AGG_SUM, AGG_PROBOR = 0, 1, 2
DEF_CENTROID, DEF_BISECTOR, DEF_MOM, DEF_SOM, DEF_LOM, DEF_WTAVER, DEF_WTSUM = range(7)
# output kinds
OUT_PWL, OUT_SINGLETON, OUT_SUGENO = 0, 1, 2

# status bits returned by eval_compiled
CLAMPED, NO_RULE, NAN_INPUT = 1, 2, 4

# a piece (one implied set) holds up to PIECE_VERTS vertices (x, left value, right value)
PIECE_VERTS = 8
PIECE_STRIDE = 1 + 3 * PIECE_VERTS

#: relative tolerance for "equal to the maximum" in mom / som / lom
MAX_RTOL = 1e-12
#: relative tolerance (of the total area) for a half-area point in a zero gap (bisector)
GAP_RTOL = 1e-12

CODES = {
    "and": {"min": AND_MIN, "prod": AND_PROD},
    "or": {"max": OR_MAX, "probor": OR_PROBOR},
    "implication": {"min": IMP_MIN, "prod": IMP_PROD},
    "aggregation": {"max": AGG_MAX, "sum": AGG_SUM, "probor": AGG_PROBOR},
    "defuzzifier": {"centroid": DEF_CENTROID, "bisector": DEF_BISECTOR, "mom": DEF_MOM,
                    "som": DEF_SOM, "lom": DEF_LOM, "wtaver": DEF_WTAVER,
                    "wtsum": DEF_WTSUM},
}
