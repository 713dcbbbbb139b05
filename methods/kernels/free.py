"""Placeholders for the names a kernel template leaves free (bound in each generated module).

N: state dimension; f(y, par) -> tuple: the (possibly modified) vector field; fjac(y, par, J): its
Jacobian into an N x N array; to_tuple(a), shifted(y, Z, j), store(t, A, j): tuple/array helpers.
"""


def _unbound(*args):  # pragma: no cover - only reached if a template is called un-generated
    raise RuntimeError("kernel template called outside a generated module")


N = S = NI = NE = NEWTON_MAXIT = FIXED_POINT_AT = 0
A = C = D = I_IDX = E_IDX = ()
EXPLICIT = False
f = fjac = to_tuple = shifted = store = _unbound
lu_solve = newton_done = _unbound
invariants = make_ws = step = post_step = project = record_row = to_tuple_shift = _unbound
dense_from_stages = dense_eval = dense_slope = _unbound
# compensated summation (methods/summation.py): the ``_sum`` forms of the steps and the carries
COMPENSATED = False
step_sum = _unbound
carry_sum = carry_add = carry_apply = carry_zero = _unbound
# the adaptive loop's family parts (methods/kernels/adaptive.py, pair.py, extrapolation.py)
ACCEPT = REJECT = UNSTABLE = 0
adaptive_ws = attempt = attempt_stages = attempt_outcome = first_step = _unbound
controller_init = controller_state = controller_clip = controller_prepare = _unbound
controller_accept = controller_reject = _unbound
# after an accepted step (methods/kernels/sampling.py), bound per driver family
grid_rows = section_rows = GRID_SAMPLE = _unbound
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
# slots of the resumable state st and rows of y_io (methods/kernels/slots.py)
ST_STARTED = ST_STEPS = ST_NFEV = ST_NJEV = ST_REJECTED = ST_LAST_ROW = ST_T = ST_H = 0
ST_CONTROL = ST_REJECT = ST_T_CARRY = 0
ST_KOUT = ST_TCOMP = ST_FOUND = ST_WANTED = ST_NEWTON = ST_SUBSTEPS = ST_MAX_G = ST_LOC_NFEV = 0
ST_ROLLBACKS = ST_WALKS = ST_HENON_FAILED = 0
ROW_Y = ROW_F = ROW_CARRY = 0
GRID_ULPS = 0.0
# the kernel codes of gnibench.suite.foundation.status.Status (emitted by kernel_constants)
STATUS_OK = STATUS_NONFINITE = STATUS_NEWTON_FAILED = STATUS_MAX_STEPS = STATUS_STEP_TOO_SMALL = 0
STATUS_BUFFER_FULL = STATUS_PAUSED = 0
