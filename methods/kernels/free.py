"""Placeholders for the names a kernel template leaves free (bound in each generated module).

N: state dimension; f(y, par) -> tuple: the (possibly modified) vector field; fjac(y, par, J): its
Jacobian into an N x N array; to_tuple(a), shifted(y, Z, j), store(t, A, j): tuple/array helpers.
"""


def _unbound(*args):  # pragma: no cover - only reached if a template is called un-generated
    raise RuntimeError("kernel template called outside a generated module")


N = S = NI = NE = NEWTON_MAXIT = FIXED_POINT = 0
A = C = D = I_IDX = E_IDX = ()
EXPLICIT = False
f = fjac = to_tuple = shifted = store = _unbound
lu_solve = newton_done = _unbound
invariants = make_ws = step = post_step = project = record_row = step_err = to_tuple_shift = _unbound
step_stages = dense_from_stages = dense_eval = dense_slope = _unbound
# section functions of the problem (problems/codegen.py), Hénon's locator (methods/events.py), the
# event helpers (methods/kernels/events.py) and the per-family names they are renamed to
section_g_0 = section_cond_0 = section_grad_0 = henon_locate = _unbound
crosses = section_event = henon_crossing = dense_crossing = dense_root_time = _unbound
grid_sample_fixed = grid_sample_adaptive = PARTIAL = ROOT_VALUE = ROOT_SLOPE = _unbound
partial_adaptive = _unbound
henon_run = flow_run = henon_join = henon_state = henon_slope = _unbound
HENON_RTOL = 0.0
HENON_MAX_SUBSTEPS = HENON_WALK_MAX = 0
HENON_STAGES = 0.0
BETA = EXPO = FAC1 = FAC2 = SAFE = DENSE_NFEV = 0.0
IORD = STAGES_NEW = 0
FSAL = DENSE_OUTPUT = GRID = GRIDDED = SECTION = SECTION_DENSE = WITH_STAGES = False
# slots of the resumable state st (methods/kernels/slots.py)
ST_KOUT = ST_TCOMP = ST_FOUND = ST_WANTED = ST_NEWTON = ST_SUBSTEPS = ST_MAX_G = ST_LOC_NFEV = 0
ST_ROLLBACKS = ST_WALKS = ST_HENON_FAILED = 0
GRID_ULPS = 0.0
# the kernel codes of gnibench.suite.foundation.status.Status (emitted by kernel_constants)
STATUS_OK = STATUS_NONFINITE = STATUS_NEWTON_FAILED = STATUS_MAX_STEPS = STATUS_STEP_TOO_SMALL = 0
STATUS_BUFFER_FULL = STATUS_PAUSED = 0
