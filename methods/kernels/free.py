"""Placeholders for the names a kernel template leaves free (bound in each generated module).

N: state dimension; f(y, par) -> tuple: the (possibly modified) vector field; fjac(y, par, J): its
Jacobian into an N x N array; to_tuple(a), shifted(y, Z, j), store(t, A, j): tuple/array helpers.
"""


def _unbound(*args):  # pragma: no cover - only reached if a template is called un-generated
    raise RuntimeError("kernel template called outside a generated module")


N = S = NI = NE = NEWTON_MAXIT = 0
A = C = D = I_IDX = E_IDX = ()
EXPLICIT = False
f = fjac = to_tuple = shifted = store = _unbound
lu_solve = newton_done = _unbound
invariants = make_ws = step = post_step = project = record_row = step_err = to_tuple_shift = _unbound
step_stages = dense_from_stages = dense_eval = _unbound
BETA = EXPO = FAC1 = FAC2 = SAFE = DENSE_NFEV = 0.0
IORD = STAGES_NEW = 0
FSAL = DENSE_OUTPUT = False
# the kernel codes of gnibench.suite.foundation.status.Status (emitted by kernel_constants)
STATUS_OK = STATUS_NONFINITE = STATUS_NEWTON_FAILED = STATUS_MAX_STEPS = STATUS_STEP_TOO_SMALL = 0
STATUS_BUFFER_FULL = STATUS_PAUSED = 0
