"""Type stub of the compiled kernel (src/kernel/module.cpp and the bind_*.cpp it calls)."""

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

_F = NDArray[np.float64]

SOURCE_HASH: str
RANK_RTOL: float
CONSISTENCY_TOL: float
ACTIVE_TOL: float
STEP_RTOL: float
ROUNDING: float
TIE_RTOL: float
PRICE_TOL: float
PIVOT_TOL: float
EMPTY_BOX_CODE: int

class Factor:
    U: _F
    sigma: _F
    V: _F
    N: _F

class Affine:
    x0: _F
    factor: Factor

class Basis:
    P: _F
    N: _F
    rank: int
    nullity: int
    sigma_max: float
    qr: bool

class Rows:
    C: _F
    e: _F
    kind: NDArray[np.int8]
    index: NDArray[np.int64]

class Residuals:
    eq: float
    box: float
    row: float

class Certificate:
    finite: bool
    eq: float
    box: float
    row: float
    eq_limit: float
    kkt: int
    objective: float
    active_lower: NDArray[np.bool_]
    active_upper: NDArray[np.bool_]
    active_rows: list[int]

class StepAnswer:
    code: int
    x: _F
    conflicts: list[int]
    nullity: int
    iterations: int

class CertifiedStep:
    code: int
    x: _F
    conflicts: list[int]
    nullity: int
    iterations: int
    basis: Basis
    rows: Rows
    certificate: Certificate | None

class DenseQPResult:
    status: int
    t: _F
    active: list[int]
    multipliers: list[float]
    blocking: int
    iterations: int

class NNLSResult:
    x: _F
    rnorm: float
    converged: bool

class ScaleLPResult:
    status: int
    t: _F
    s: float
    rows: list[int]

class Box:
    lower: _F
    upper: _F
    lower_by: NDArray[np.int64]
    upper_by: NDArray[np.int64]
    nan_limit: int

class RateBox:
    lower: _F
    upper: _F

class SingularValues:
    leader: float
    follower: float

def factor(A: ArrayLike) -> Factor: ...
def affine(A: ArrayLike, b: ArrayLike) -> Affine | None: ...
def inequalities(lower: ArrayLike, upper: ArrayLike, G: ArrayLike, h: ArrayLike) -> Rows: ...
def least_distance(N: ArrayLike, x0: ArrayLike, w_diag: ArrayLike, w_full: ArrayLike,
                   root_full: ArrayLike, center: ArrayLike) -> _F: ...
def basis(A: ArrayLike) -> Basis: ...
def solve_nullspace(A: ArrayLike, b: ArrayLike, basis: Basis, C: ArrayLike, e: ArrayLike,
                    w_diag: ArrayLike, w_full: ArrayLike, root_full: ArrayLike,
                    center: ArrayLike, feas_tol: float, max_iter: int) -> StepAnswer: ...
def dense_qp(R: ArrayLike, t_free: ArrayLike, M: ArrayLike, f: ArrayLike, feas_tol: float,
             max_iter: int) -> DenseQPResult: ...
def nnls(A: ArrayLike, b: ArrayLike, max_iter: int) -> NNLSResult: ...
def residuals(A: ArrayLike, b: ArrayLike, lower: ArrayLike, upper: ArrayLike,
              G: ArrayLike, h: ArrayLike, x: ArrayLike) -> Residuals: ...
def kkt_holds(A: ArrayLike, b: ArrayLike, basis: Basis, C: ArrayLike, e: ArrayLike,
              w_diag: ArrayLike, w_full: ArrayLike, root_full: ArrayLike, center: ArrayLike,
              x: ArrayLike, bounds: bool) -> bool: ...
def certificate(A: ArrayLike, b: ArrayLike, lower: ArrayLike, upper: ArrayLike,
                G: ArrayLike, h: ArrayLike, basis: Basis | None, C: ArrayLike, e: ArrayLike,
                kind: ArrayLike, index: ArrayLike, w_diag: ArrayLike, w_full: ArrayLike,
                root_full: ArrayLike, center: ArrayLike, x: ArrayLike, bounds: bool,
                eq_rtol: float, bounds_tol: float, ask_kkt: bool) -> Certificate: ...
def solve_certified(A: ArrayLike, b: ArrayLike, lower: ArrayLike, upper: ArrayLike,
                    G: ArrayLike, h: ArrayLike, w_diag: ArrayLike, w_full: ArrayLike,
                    root_full: ArrayLike, center: ArrayLike, feas_tol: float,
                    max_iter: int, bounds: bool, eq_rtol: float, bounds_tol: float
                    ) -> CertifiedStep: ...

def intersect_boxes(lowers: ArrayLike, lower_ids: Sequence[int], uppers: ArrayLike,
                    upper_ids: Sequence[int], n: int, pin_rtol: float) -> Box: ...
def first_defect(finite: Sequence[ArrayLike], not_nan: Sequence[ArrayLike]) -> int: ...
def step_kinematics(carry: Chain, q_carry: ArrayLike, carry_frames: Sequence[int],
                    follower: Chain, q_f: ArrayLike, follower_tool: int, T_D: ArrayLike,
                    n_l: int, T: _F, J: _F, J_f: _F, e: _F, sv: _F) -> None: ...
def step_errors(carry: Chain, q_carry: ArrayLike, carry_frames: Sequence[int],
                follower: Chain, q_f: ArrayLike, follower_tool: int, T_D: ArrayLike,
                e: _F) -> None: ...
class PredictedErrors:
    finite: bool
    tracking_position: float
    tracking_rotation: float
    closure_position: float
    closure_rotation: float
def predicted_errors(carry: Chain, carry_frames: Sequence[int], follower: Chain,
                     follower_tool: int, q_l: ArrayLike, q_f: ArrayLike, sigma_f: float,
                     sigma_l: float, x: ArrayLike, col_rate: ArrayLike, dt: float,
                     T_D: ArrayLike) -> PredictedErrors: ...
def pose_error(T_star: ArrayLike, T: ArrayLike, e: _F) -> None: ...
def negligible(x: ArrayLike, n_l: int, n_f: int, dt: float, T_tool: ArrayLike,
               T_target: ArrayLike, length_l: float, length_f: float, budget_pos: float,
               budget_rot: float, share: float) -> bool: ...
def ik_dls(chain: Chain, tool: int, T_target: ArrayLike, q: _F, lo: ArrayLike,
           hi: ArrayLike, tol_pos: float, tol_rot: float, max_iter: int, damping: float,
           mu_min: float, mu_max: float) -> IKAnswer: ...
class IKAnswer:
    iterations: int
    position_error: float
    rotation_error: float
    stop: int
def range_box(lo: ArrayLike, hi: ArrayLike, rec: ArrayLike, off: ArrayLike) -> RateBox: ...
def centre(lo: ArrayLike, hi: ArrayLike, centred: ArrayLike, shrink: float) -> _F: ...
def smallest_singular_value(J: ArrayLike) -> float: ...
def smallest_singular_values(J_leader: ArrayLike, J_follower: ArrayLike
                             ) -> SingularValues: ...
def carry_equality(n_l: int, J_object: ArrayLike, J_target: ArrayLike, J_f: ArrayLike,
                   twist: ArrayLike, e_l: ArrayLike, e_c: ArrayLike, scale: float,
                   gain_l: float, gain_c: float, exact_orientation: bool, A: _F, b: _F
                   ) -> bool: ...
def scale_lp(M: ArrayLike, a: ArrayLike, g: ArrayLike, s_lo: float, s_hi: float
             ) -> ScaleLPResult: ...

class ClosestPoints:
    s: _F
    t: _F
    x: _F
    y: _F

class CapsuleProximities:
    distance: _F
    point_a: _F
    point_b: _F
    normal: _F

class CapsuleProximity:
    distance: float
    point_a: _F
    point_b: _F
    normal: _F

class SceneProximities:
    finite: bool
    pairs: NDArray[np.int64]
    distance: _F
    point_a: _F
    point_b: _F
    normal: _F

class DamperRows:
    finite: bool
    pairs: NDArray[np.int64]
    G: _F
    h: _F

def segment_closest_points(p0: ArrayLike, p1: ArrayLike, q0: ArrayLike, q1: ArrayLike
                           ) -> ClosestPoints: ...
def capsule_proximities(a0: ArrayLike, a1: ArrayLike, ra: ArrayLike, b0: ArrayLike,
                        b1: ArrayLike, rb: ArrayLike) -> CapsuleProximities: ...
class CoalPairs:
    def __init__(self, kinds: Sequence[int], params: ArrayLike, local: ArrayLike,
                 ia: Sequence[int], ib: Sequence[int], boxed: Sequence[bool],
                 gjk_tolerance: float, epa_tolerance: float) -> None: ...
    @property
    def n_pairs(self) -> int: ...
    def measure(self, pair: int, frame_a: ArrayLike, frame_b: ArrayLike
                ) -> CapsuleProximity: ...
    def lower_bound(self, pair: int, frame_a: ArrayLike, frame_b: ArrayLike,
                    a0: ArrayLike, a1: ArrayLike, ra: float, b0: ArrayLike, b1: ArrayLike,
                    rb: float) -> float: ...
def scene_proximities(frames: ArrayLike, body_frame: Sequence[int], a_local: ArrayLike,
                      b_local: ArrayLike, r: ArrayLike, sphere: ArrayLike,
                      ia: Sequence[int], ib: Sequence[int], within: float,
                      exact: CoalPairs | None = None) -> SceneProximities: ...
class DamperScene:
    def __init__(self, body_frame: Sequence[int], a_local: ArrayLike, b_local: ArrayLike,
                 r: ArrayLike, sphere: ArrayLike, ia: Sequence[int], ib: Sequence[int],
                 exact: CoalPairs | None, owner: Sequence[int], model_frame: Sequence[int],
                 leader_frames: Sequence[int], follower_frames: Sequence[int], d_i: float,
                 d_s: float, gain: float, zero_row: float, n_l: int, n_f: int,
                 grasp_start: int, n: int) -> None: ...
    def rows(self, leader: Chain, follower: Chain, J_object: ArrayLike, T_object: ArrayLike
             ) -> DamperRows: ...
def damper_rows(leader: Chain, follower: Chain, J_object: ArrayLike,
                object_origin: ArrayLike, owners: Sequence[int], frames: Sequence[int],
                point_a: ArrayLike, point_b: ArrayLike, normal: ArrayLike, n_l: int,
                n_f: int, grasp_start: int, n: int) -> _F: ...

def split_operator(points: ArrayLike, free: Sequence[ArrayLike], centre: ArrayLike,
                   mass: float, fallback_length: float, rcond_min: float) -> _F: ...

def load_torques(leader: Chain, leader_tool: int, follower: Chain, follower_tool: int,
                 q_l: ArrayLike, q_f: ArrayLike, gravity: ArrayLike, mass: float,
                 points: Sequence[ArrayLike], free: Sequence[Sequence[ArrayLike]],
                 centres: Sequence[ArrayLike], grasp_step: float, fallback_length: float,
                 rcond_min: float) -> LoadTorques: ...

PINOCCHIO_VERSION: str
COAL_VERSION: str

class Chain:
    def __init__(self, parents: list[int], kinds: list[int], axes: ArrayLike,
                 placements: ArrayLike, frame_parents: list[int],
                 frame_placements: ArrayLike) -> None: ...
    @property
    def nq(self) -> int: ...
    @property
    def njoints(self) -> int: ...
    @property
    def nframes(self) -> int: ...
    @property
    def updates(self) -> int: ...
    @property
    def q(self) -> _F: ...
    def set_joint_placement(self, joint: int, T: ArrayLike) -> None: ...
    def set_frame_placement(self, frame: int, T: ArrayLike) -> None: ...
    def update(self, q: ArrayLike) -> None: ...
    def compute(self, q: ArrayLike, pose_frames: Sequence[int], jac_frames: Sequence[int],
                T: _F, J: _F) -> None: ...
    def poses(self, q: ArrayLike, frames: Sequence[int], T: _F) -> None: ...  # FK only
    def __getstate__(self) -> dict[str, Any]: ...
    def __setstate__(self, state: dict[str, Any]) -> None: ...
    def frame_poses(self, frames: Sequence[int], T: _F) -> None: ...
    def frame_jacobian(self, frame: int, J: _F) -> None: ...
    def set_inertia(self, joint: int, mass: float, lever: ArrayLike,
                    inertia: ArrayLike) -> None: ...
    def set_gravity(self, g: ArrayLike) -> None: ...
    def static_torques(self, q: ArrayLike, frame: int, wrench: ArrayLike,
                       point: ArrayLike | None, derivatives: bool) -> StaticTorques: ...

def braking_bound(D: ArrayLike, delta: ArrayLike, dt: ArrayLike) -> _F: ...
class Context:
    n_l: int
    n_f: int
    k: int
    n: int
    t: float
    dt: float
    scale_max: float
    T_tool: _F
    T_object: _F
    T_target: _F
    T_f: _F
    J_tool: _F
    J_object: _F
    J_target: _F
    J_f: _F
    leader_error: _F
    closure_error: _F
    twist: _F
    positions: _F
    rate_lo: _F
    rate_hi: _F
    x_applied: _F
    def __init__(self, rate_lo: ArrayLike, rate_hi: ArrayLike,
                 x_applied: ArrayLike | None = None, dt: float = 1.0,
                 scale_max: float = 1.0) -> None: ...

class Equality:
    A: _F
    b: _F
    names: tuple[str, ...]
    def __init__(self, A: ArrayLike, b: ArrayLike, names: Sequence[str] = ()) -> None: ...

class Quadratic:
    weights: _F
    center: _F
    def __init__(self, w: ArrayLike | None = None, W: ArrayLike | None = None, *,
                 center: ArrayLike) -> None: ...

class Constraint:
    lower: _F | None
    upper: _F | None
    G: _F | None
    h: _F | None
    row_names: tuple[str, ...]
    nonfinite: str
    def __init__(self, lower: ArrayLike | None = None, upper: ArrayLike | None = None,
                 G: ArrayLike | None = None, h: ArrayLike | None = None,
                 row_names: Sequence[str] = ()) -> None: ...

class StepOut:
    context: Context
    A: _F
    b: _F
    eq_names: tuple[str, ...]
    weights: _F
    center: _F
    lower: _F
    upper: _F
    lower_by: NDArray[np.int64]
    upper_by: NDArray[np.int64]
    lower_names: tuple[str, ...]
    upper_names: tuple[str, ...]
    G: _F
    h: _F
    row_names: tuple[str, ...]
    row_limit: list[int]
    recovering: NDArray[np.bool_]
    any_recovering: bool
    failed_part: int
    failed_kind: str
    failure: str
    kinematics_seconds: float
    seconds: float
    def __init__(self) -> None: ...
    def sigma_min(self) -> tuple[float, float]: ...

class Task:
    weight: float
    def __init__(self) -> None: ...

class CostTerm:
    def __init__(self) -> None: ...

class Limit:
    def __init__(self) -> None: ...

class ObjectPathTask(Task):
    gain: float
    def __init__(self, gain: float) -> None: ...
    def equality(self, ctx: object) -> Equality: ...

class GraspClosureTask(Task):
    gain: float
    exact_orientation: bool
    def __init__(self, gain: float, exact_orientation: bool) -> None: ...
    def equality(self, ctx: object) -> Equality: ...

class CentringCost(CostTerm):
    def __init__(self, weights: ArrayLike, centred: ArrayLike, shrink: float) -> None: ...
    def quadratic(self, ctx: object) -> Quadratic: ...

class RangeLimit(Limit):
    size: int
    def __init__(self, recovery: ArrayLike, off: ArrayLike) -> None: ...
    def constraint(self, ctx: object) -> Constraint: ...

class SpeedLimit(Limit):
    size: int
    def __init__(self, v_max: ArrayLike) -> None: ...
    def constraint(self, ctx: object) -> Constraint: ...

class AccelerationLimit(Limit):
    size: int
    def __init__(self, delta: ArrayLike) -> None: ...
    def constraint(self, ctx: object) -> Constraint: ...

class CollisionLimit(Limit):
    def __init__(self, damper: DamperScene, names: Sequence[str], nonfinite: str) -> None: ...
    def constraint(self, ctx: object) -> Constraint: ...

def problem_check(A: _F, b: _F, weights: _F, center: _F, lower: _F, upper: _F, G: _F,
                  h: _F) -> int: ...

class SlidePath:
    def __init__(self, revolute: bool, axis: int, placement: ArrayLike, child: ArrayLike,
                 rate: float) -> None: ...
    def at(self, sigma: float) -> _F: ...

class TorqueLimit(Limit):
    def __init__(self, leader: Chain, leader_tool: int, follower: Chain, follower_tool: int,
                 tau_max: ArrayLike, row_names: Sequence[str], mass: float | None,
                 mass_centre: ArrayLike, gravity: ArrayLike, follower_path: SlidePath,
                 leader_path: SlidePath | None, grasp_step: float, fallback_length: float,
                 rcond_min: float) -> None: ...
    approach: float
    def constraint(self, ctx: object) -> Constraint: ...

class SupportLine:
    held: bool
    sigma_min: float
    sigma_max: float
    sigma_inf: float
    lever: float
    gravity: _F
    origin: _F
    direction: _F
    pose0: _F
    def push(self, sigma: float) -> float: ...

class SupportPlane:
    def __init__(self, mass: float, mass_centre: ArrayLike, gravity: ArrayLike, r1: ArrayLike,
                 normal: ArrayLike, offset: float, r_min: ArrayLike, r_max: ArrayLike,
                 gravity_min: float) -> None: ...
    def line(self, R_world_object: ArrayLike) -> SupportLine: ...
    def __getstate__(self) -> dict[str, Any]: ...
    def __setstate__(self, state: dict[str, Any]) -> None: ...

class Step:
    def __init__(self, n_l: int, n_f: int, carry_frames: Sequence[int], follower_tool: int,
                 cols: Sequence[int], q_min: ArrayLike, q_max: ArrayLike, dt: float,
                 ranged: ArrayLike, pin_rtol: float) -> None: ...
    def add_task(self, task: Task) -> None: ...
    def add_cost(self, cost: CostTerm) -> None: ...
    def add_limit(self, limit: Limit) -> None: ...
    def set_labels(self, labels: Sequence[str]) -> None: ...
    def add_grasp_line(self, origin: ArrayLike, direction: ArrayLike, r_min: ArrayLike,
                       r_max: ArrayLike, sigma_min: float, sigma_max: float) -> None: ...
    def set_grasp_line(self, grasp: int, origin: ArrayLike, direction: ArrayLike,
                       r_min: ArrayLike, r_max: ArrayLike, sigma_min: float,
                       sigma_max: float) -> None: ...
    @property
    def n(self) -> int: ...
    @property
    def grasp_lines(self) -> bool: ...
    def build(self, out: StepOut, carry: Chain, q_carry: ArrayLike, col_rate: ArrayLike,
              follower: Chain, q_f: ArrayLike, T_D: ArrayLike, twist: ArrayLike,
              sigmas: ArrayLike, grasp_lo: ArrayLike, grasp_hi: ArrayLike,
              x_applied: ArrayLike, t: float, scale_max: float, user: object) -> None: ...

class StaticTorques:
    tau: _F
    dtau: _F
    J: _F

class LoadTorques:
    tau: _F
    D: _F
    w: _F

class RateRange:
    lower: float
    upper: float

def grasp_rate_range(r: ArrayLike, s_star: ArrayLike, r_min: ArrayLike, r_max: ArrayLike,
                     dt: float) -> RateRange: ...
def grasp_rates(point: ArrayLike, tangent: ArrayLike, sigma: float, r_min: ArrayLike,
                r_max: ArrayLike, sigma_min: float, sigma_max: float, dt: float
                ) -> RateRange: ...

class WaypointPath:
    def __init__(self, times: Sequence[float], poses: ArrayLike) -> None: ...
    def pose(self, t: float, T: _F) -> None: ...
    def derivative(self, t: float, order: int, out: _F) -> None: ...
    def __getstate__(self) -> dict[str, Any]: ...
    def __setstate__(self, state: dict[str, Any]) -> None: ...
