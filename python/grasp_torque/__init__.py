"""grasp_torque: the joint torques a dexterous hand should apply to hold an object.

Jia et al.'s key-constraint-set method with the consistency constraints that make the
torques hold the object, in Rust. One grasp::

    import grasp_torque as gt
    solver = gt.Solver("fixtures/hand3-pcwf.json", sides=8)
    r = solver.solve()                 # or solver.solve(wrench)
    r.status, r.torque, r.objective, r.residuals

Many grasps, straight from numpy, in parallel with the GIL released::

    out = gt.solve_batch(G, JT, W, contacts=[{"model": "pcwf", "mu": 0.5}] * 3)
    out.torque, out.objective, out.wrench_residual, out.status

Status codes of ``solve_batch`` (``STATUS_CODES`` maps them to names):

====  ==================  =====================================================
code  name                meaning
====  ==================  =====================================================
0     optimal             an optimal torque that passed the residual checks
1     almost_optimal      reduced accuracy (Clarabel), residual checks passed
2     infeasible          no torque holds the object within the cones/limits
3     iteration_limit     the backend stopped before optimality
4     numerical_failure   the backend failed, or its answer failed the checks
5     invalid             this item's input was rejected (see ``errors``)
====  ==================  =====================================================

Items without an answer (codes 2-5) have NaN torque, objective and residual.
"""

from __future__ import annotations

import json
import math
import numbers
import os
import re
from typing import Any, Dict, Iterable, List, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _native

__all__ = [
    "Problem",
    "Solver",
    "Hand",
    "HandBatchResult",
    "HandArrays",
    "Result",
    "solve_batch",
    "BatchResult",
    "STATUS_CODES",
    "INVALID",
    "backends",
    "synthetic_grasps",
    "Array",
    "BatchErrors",
    "Contacts",
    "MinNormalForce",
    "ProblemLike",
    "TorqueLimits",
]

__version__ = _native.VERSION

#: A float64 array, as every output is.
Array = NDArray[np.float64]
#: Contact dicts, one per contact: ``{"model": "pcwf", "mu": 0.5}``, and for a hand a
#: ``link`` or ``site``.
Contacts = Sequence[Mapping[str, Any]]
#: Per joint (or actuator) a number t (``|τ| ≤ t``), ``[lower, upper]`` (``None`` or
#: ``∓inf`` for an open side) or ``None`` / ``inf`` for none; an ``[m, 2]`` array; or,
#: for a hand, ``"model"`` (the file's limits).
TorqueLimits = Union[str, ArrayLike, Sequence[Union[None, float, Sequence[Optional[float]]]]]
#: One number for every contact, or one per contact.
MinNormalForce = Union[float, Sequence[float]]
#: A batch's ``errors``: the item (``b``, or ``(b, k)`` with K wrenches per grasp) and
#: why it was rejected.
BatchErrors = Dict[Union[int, Tuple[int, int]], str]

Result = _native.Result

STATUS_CODES = {
    0: "optimal",
    1: "almost_optimal",
    2: "infeasible",
    3: "iteration_limit",
    4: "numerical_failure",
    5: "invalid",
}
INVALID = _native.INVALID


def backends() -> List[str]:
    """The backends compiled into this build (``active-set``, ``clarabel``)."""
    return list(_native.backends())


def _plain(o: Any) -> Any:
    """JSON fallback: numpy arrays and scalars as lists and numbers."""
    if hasattr(o, "tolist"):
        return o.tolist()
    if isinstance(o, os.PathLike):
        return os.fspath(o)
    raise TypeError(f"{type(o).__name__} is not JSON serialisable")


def _non_finite(obj: Any, path: str = "") -> Optional[Tuple[str, Any]]:
    """The path (``contacts[0].mu``, ``grasp_matrix[1][2]``, as the Rust side names
    fields) and value of the first number in ``obj`` that is not finite, or None."""
    if hasattr(obj, "tolist"):
        obj = obj.tolist()
    if isinstance(obj, float):
        return None if math.isfinite(obj) else (path or "(input)", obj)
    if isinstance(obj, Mapping):
        items = ((f"{path}.{k}" if path else str(k), v) for k, v in obj.items())
    elif isinstance(obj, (list, tuple)):
        items = ((f"{path}[{i}]", v) for i, v in enumerate(obj))
    else:
        return None
    for p, v in items:
        found = _non_finite(v, p)
        if found is not None:
            return found
    return None


def _dumps(obj: Any) -> str:
    # allow_nan=False: NaN is not JSON; the message names the field and the value
    # instead of a parse error deep in the Rust reader.
    try:
        return json.dumps(obj, default=_plain, allow_nan=False)
    except ValueError:
        found = _non_finite(obj)
        if found is None:
            raise
        path, value = found
        raise ValueError(f"{path}: expected a finite number, got {value}") from None


def _real(name: str, a: Any) -> Array:
    """``a`` as a C-contiguous float64 array. What is not real numbers is refused by
    name: numpy would drop an imaginary part with a warning, read strings as numbers,
    or fail on a ragged list without saying which argument."""
    try:
        arr = np.asarray(a)
    except ValueError as e:
        raise ValueError(f"{name}: expected a rectangular array of numbers ({e})") from None
    kind = arr.dtype.kind
    if kind == "c":
        raise ValueError(f"{name}: expected real numbers, got complex values ({arr.dtype})")
    if kind in "USV":
        raise ValueError(f"{name}: expected real numbers, got {arr.dtype} values")
    try:
        return np.ascontiguousarray(arr, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name}: expected real numbers ({e})") from None


def _count(name: str, v: Any, least: int, most: Optional[int] = None) -> int:
    """A whole number from ``least`` to ``most``, or a ``ValueError`` naming ``name``."""
    if isinstance(v, bool) or not isinstance(v, numbers.Integral):
        raise ValueError(f"{name}: expected a whole number, got {v!r}")
    n = int(v)
    if n < least:
        raise ValueError(f"{name}: expected at least {least}, got {n}")
    if most is not None and n > most:
        raise ValueError(f"{name}: expected at most {most}, got {n}")
    return n


def _limits(limits: Any) -> Any:
    """Torque limits as the files write them: per joint a number t (``|τ| ≤ t``), a
    pair ``[lower, upper]``, or ``None`` (JSON ``null``) for none, which numpy users
    write ``inf`` (``-inf`` for a pair's open lower side)."""
    if limits is None or isinstance(limits, str):
        return limits
    if hasattr(limits, "tolist"):
        limits = limits.tolist()
    if not isinstance(limits, (list, tuple)):
        return limits

    def one(v: Any) -> Any:
        if hasattr(v, "tolist"):
            v = v.tolist()
        if isinstance(v, (list, tuple)) and len(v) == 2:
            lo, hi = v
            return [None if lo == -math.inf else lo, None if hi == math.inf else hi]
        return None if isinstance(v, float) and v == math.inf else v

    return [one(v) for v in limits]


def _gravity(gravity: Any, B: int) -> Tuple[Any, Optional[Array]]:
    """``gravity`` as the hand form's value and, when given per grasp (``[B, 3]``), the
    rows: ``(None | "model" | [gx, gy, gz], None | ndarray[B, 3])``. Per grasp, the
    hand form gets a zero vector, so that the masses are checked once for the batch."""
    if gravity is None or isinstance(gravity, str):
        return gravity, None
    g = _real("gravity", gravity)
    if g.shape == (3,):
        return g.tolist(), None
    if g.ndim == 2 and g.shape == (B, 3):
        return [0.0, 0.0, 0.0], g
    raise ValueError(
        f"gravity: expected [gx, gy, gz], [B, 3] = ({B}, 3) or \"model\", got shape {g.shape}"
    )


def _contacts(contacts: Any) -> List[Mapping[str, Any]]:
    """The contact list, one dict per contact."""
    if isinstance(contacts, (Mapping, str, bytes)) or not isinstance(contacts, Iterable):
        raise ValueError(
            "contacts: expected a list of contact dicts, one per contact, such as "
            f"{{'model': 'pcwf', 'mu': 0.5}}; got {type(contacts).__name__}"
        )
    return list(contacts)


class Problem:
    """A validated grasp problem.

    Build one from a file (``Problem.load(path)``), from a dict in any of the JSON forms
    (``Problem.from_dict(d)``: matrix form with ``grasp_matrix`` and
    ``jacobian_transpose``, geometry form with ``fingers``, hand form with ``hand``), or
    from arrays (``Problem.from_arrays(G, JT, contacts, wrench)``). Invalid input raises
    ``ValueError`` with the command line's message.
    """

    __slots__ = ("_p",)

    def __init__(self, native: "_native.Problem"):
        self._p = native

    @classmethod
    def load(cls, path: Union[str, "os.PathLike[str]"]) -> "Problem":
        path = os.fspath(path)
        try:
            with open(path, encoding="utf-8") as f:
                text = f.read()
        except OSError as e:
            raise ValueError(f"{path}: {e.strerror}") from None
        try:
            return cls(_native.Problem.from_json(text, os.path.dirname(path) or "."))
        except ValueError as e:
            raise ValueError(f"{path}: {e}") from None

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], base: Union[str, "os.PathLike[str]"] = ".") -> "Problem":
        """A problem from a dict in any JSON form; a hand's relative ``model`` path is
        taken relative to ``base``."""
        try:
            return cls(_native.Problem.from_json(_dumps(d), os.fspath(base)))
        except ValueError as e:
            # The line and column are those of the JSON written from the dict.
            raise ValueError(re.sub(r" \(line \d+, column \d+\)$", "", str(e))) from None

    @classmethod
    def from_arrays(
        cls,
        grasp_matrix: ArrayLike,
        jacobian_transpose: ArrayLike,
        contacts: Contacts,
        wrench: Optional[ArrayLike] = None,
        **options: Any,
    ) -> "Problem":
        """A matrix-form problem: G (6 × n), Jᵀ (m × n), one contact dict per contact
        (``{"model": "pcwf", "mu": 0.5}``; ``sfcl``/``sfce`` add ``mu_torsion``), the
        wrench (default zero) and any option of the matrix form (``torque_weights``,
        ``torque_limits`` (per joint t, ``[lower, upper]``, or ``None`` or ``inf`` for none),
        ``min_normal_force``, ``joint_names``, ``linearization``, ``internal_forces``,
        ``initial_torque``, ``transmission`` (m × a: τ = T u, the solve then returns
        actuator forces u), ``actuator_names``, ``passive_torque`` (m: the joints'
        spring or weight torques, ``Jᵀ f = T u + passive_torque``))."""
        d = {
            "grasp_matrix": _real("grasp_matrix", grasp_matrix),
            "jacobian_transpose": _real("jacobian_transpose", jacobian_transpose),
            "wrench": np.zeros(6) if wrench is None else _real("wrench", wrench),
            "contacts": _contacts(contacts),
        }
        d.update(options)
        if "torque_limits" in d:
            d["torque_limits"] = _limits(d["torque_limits"])
        return cls.from_dict(d)

    def to_dict(self) -> Dict[str, Any]:
        """The problem in matrix form (what ``grasp-torque build`` prints)."""
        d: Dict[str, Any] = json.loads(self._p.to_json())
        return d

    @property
    def hand(self) -> Optional[Dict[str, Any]]:
        """For the hand form: the robot, defaulted joints, limits source, warnings."""
        h = self._p.hand_json()
        return None if h is None else json.loads(h)

    @property
    def joints(self) -> int:
        """m, the number of joints."""
        return self._p.joints

    @property
    def force_dim(self) -> int:
        """n, contact force components."""
        return self._p.force_dim

    @property
    def contacts(self) -> int:
        """The number of contacts."""
        return self._p.contacts

    @property
    def joint_names(self) -> Optional[List[str]]:
        """Names, or None."""
        return self._p.joint_names

    @property
    def wrench(self) -> Array:
        """The problem's wrench w."""
        return self._p.wrench

    @property
    def grasp_matrix(self) -> Array:
        """G, 6 × n."""
        return self._p.grasp_matrix

    @property
    def jacobian_transpose(self) -> Array:
        """Jᵀ, m × n."""
        return self._p.jacobian_transpose

    @property
    def passive_torque(self) -> Optional[Array]:
        """τ_p per joint (a hand's springs and, with gravity, its links' weight), or None."""
        return self._p.passive_torque

    def __reduce__(self) -> Tuple[Any, Tuple[Any, ...]]:
        hand = self._p.hand_json()
        return (_problem_from_json, (self._p.to_json(), hand))

    def __repr__(self) -> str:
        return f"Problem(joints={self.joints}, contacts={self.contacts}, force_dim={self.force_dim})"


def _problem_from_json(text: str, hand: Optional[str] = None) -> Problem:
    return Problem(_native.Problem.from_json(text, ".", hand))


def _as_problem(problem: "ProblemLike") -> Problem:
    if isinstance(problem, Problem):
        return problem
    if isinstance(problem, (str, os.PathLike)):
        return Problem.load(problem)
    if isinstance(problem, Mapping):
        return Problem.from_dict(problem)
    raise TypeError(
        f"problem: expected a Problem, a path or a dict, got {type(problem).__name__}"
    )


def _settings(
    backend: Optional[str],
    cones: str,
    sides: Optional[int],
    latitudes: Optional[int],
    sfce_spacing: Optional[str],
    internal_forces: Optional[str],
    paper_model: bool,
) -> Dict[str, Any]:
    """The solver keywords, as the Rust side reads them (the CLI's flags)."""
    return {
        "backend": backend,
        "cones": cones,
        "sides": sides,
        "latitudes": latitudes,
        "sfce_spacing": sfce_spacing,
        "internal_forces": internal_forces,
        "paper_model": bool(paper_model),
    }


class Solver:
    """A solver for one grasp, reused across wrenches (one per control loop).

    ``Solver(problem, backend=None, cones="linear", sides=None, latitudes=None,
    internal_forces=None, paper_model=False, sfce_spacing=None, check="full")``:
    ``problem`` is a ``Problem``, a path or a dict. ``backend`` is ``"active-set"`` or ``"clarabel"`` (default: the first that
    supports the cones, active-set when it can); ``cones`` is ``"linear"`` (inscribed
    polyhedra with ``sides`` = N, ``latitudes`` = K) or ``"exact"``. ``sides``,
    ``latitudes``, ``sfce_spacing`` (``"uniform"`` or ``"paper"``) and
    ``internal_forces`` override the problem's own.

    ``solve(wrench=None, warm=True)`` solves for ``wrench`` (the problem's when None),
    warm-started from the previous optimal answer; it returns a ``Result``.

    ``check="lazy"`` is the control-loop setting: with the native backend, ``optimal``
    rests on its own from-scratch check of every row, and the contact forces,
    residuals and the independent residual check wait for ``diagnose()``, which
    returns the completed ``Result`` (and may still turn it into
    ``numerical_failure``). ``check="full"`` (the default) does all of it every solve.
    """

    __slots__ = ("_s", "_settings")

    def __init__(
        self,
        problem: "ProblemLike",
        backend: Optional[str] = None,
        cones: str = "linear",
        sides: Optional[int] = None,
        latitudes: Optional[int] = None,
        internal_forces: Optional[str] = None,
        paper_model: bool = False,
        sfce_spacing: Optional[str] = None,
        check: str = "full",
    ):
        settings = _settings(backend, cones, sides, latitudes, sfce_spacing, internal_forces, paper_model)
        settings["check"] = check
        self._settings = settings
        self._s = _native.Solver(_as_problem(problem)._p, _dumps(settings))

    def solve(self, wrench: Optional[ArrayLike] = None, warm: bool = True) -> Result:
        if wrench is None:
            return self._s.solve(None, warm)
        a = _real("wrench", wrench)
        w = a.reshape(-1)
        if w.shape != (6,):
            raise ValueError(
                f"wrench: expected 6 numbers [Fx, Fy, Fz, Mx, My, Mz], got {w.size} (shape {a.shape})"
                + ("; solve_batch takes many wrenches" if a.ndim > 1 else "")
            )
        return self._s.solve(w.tolist(), warm)

    def diagnose(self) -> Result:
        """The last answer with what ``check="lazy"`` deferred: forces, residuals and
        the independent residual check."""
        return self._s.diagnose()

    @property
    def problem(self) -> Problem:
        """The problem as solved (with the overrides applied)."""
        return Problem(self._s.problem())

    @property
    def backend(self) -> str:
        return self._s.backend

    def __reduce__(self) -> Tuple[Any, Tuple[Any, ...]]:
        return (_solver_from_state, (self.problem, self._settings))

    def __repr__(self) -> str:
        s = self._settings
        return f"Solver(backend={self.backend!r}, cones={s['cones']!r}, problem={self.problem!r})"


def _solver_from_state(problem: Problem, settings: Dict[str, Any]) -> Solver:
    return Solver(problem, **settings)


#: A problem, a path to a problem file, or a dict in any of the JSON forms.
ProblemLike = Union[Problem, str, "os.PathLike[str]", Mapping[str, Any]]


class BatchResult(NamedTuple):
    """Arrays of a batch: ``torque[B,(K,)m]``, ``objective[B,(K)]``,
    ``wrench_residual[B,(K)]`` (``‖G f − w‖∞``), ``status[B,(K)]`` (int8 codes, see
    ``STATUS_CODES``), ``errors``: ``{(grasp, wrench): message}`` for invalid items, and
    with ``contact_forces=True`` the forces ``f[B,(K,)n]`` in G's column order (each
    contact's components in its frame; NaN without an answer), else None."""

    torque: Array
    objective: Array
    wrench_residual: Array
    status: NDArray[np.int8]
    errors: BatchErrors
    contact_forces: Optional[Array] = None


_Outputs = Tuple[Array, Array, Array, NDArray[np.int8]]
_OUTPUT_NAMES = ("torque", "objective", "wrench_residual", "status")


def _out(name: str, given: Optional[NDArray[Any]], shape: Tuple[int, ...], dtype: Any) -> NDArray[Any]:
    """A preallocated output, checked (the native batch writes it in place, as the rows of
    a C-ordered buffer), or a new one."""
    if given is None:
        return np.empty(shape, dtype=dtype)
    want = np.dtype(dtype)
    if not isinstance(given, np.ndarray):
        raise ValueError(
            f"{name}: expected a numpy array of dtype {want.name} and shape {shape}, got {type(given).__name__}"
        )
    if given.dtype != want:
        got = given.dtype.name
        if got == want.name:
            got += f" in the other byte order ({given.dtype.str})"
        raise ValueError(f"{name}: expected a numpy array of dtype {want.name}, got {got}")
    if given.shape != shape:
        raise ValueError(f"{name}: expected an array of shape {shape}, got {given.shape}")
    if not given.flags.c_contiguous:
        raise ValueError(
            f"{name}: expected a C-contiguous array, got one with strides {given.strides}"
        )
    if not given.flags.writeable:
        raise ValueError(f"{name}: expected a writeable array, got a read-only one")
    return given


def _apart(outputs: Mapping[str, Optional[NDArray[Any]]], inputs: Mapping[str, Optional[NDArray[Any]]]) -> None:
    """Refuses an output that shares memory with another output or with an input: the
    native batch reads the inputs while it writes the outputs, from many threads."""
    named = [(k, v) for k, v in outputs.items() if v is not None]
    for i, (a, x) in enumerate(named):
        for b, y in named[i + 1 :]:
            if np.shares_memory(x, y):
                raise ValueError(f"{a}: shares memory with {b}; each output needs an array of its own")
        for b, y in inputs.items():
            if y is not None and np.shares_memory(x, y):
                raise ValueError(f"{a}: shares memory with the input {b}; pass an output array of its own")


def _wrenches(W: Array, B: int) -> Tuple[Array, bool]:
    """``W`` as ``[B, K, 6]``, and whether it was ``[B, 6]``; its shape as given in the
    message when it is neither."""
    if W.ndim in (2, 3) and W.shape[0] == B and W.shape[-1] == 6:
        return (W.reshape(B, 1, 6), True) if W.ndim == 2 else (W, False)
    raise ValueError(f"W: expected shape ({B}, 6) or ({B}, K, 6), got {W.shape}")


def _outputs(
    lead: Tuple[int, ...],
    m: int,
    torque: Optional[Array],
    objective: Optional[Array],
    wrench_residual: Optional[Array],
    status: Optional[NDArray[np.int8]],
) -> _Outputs:
    """A batch's four outputs, given (checked) or new."""
    return (
        _out("torque", torque, lead + (m,), np.float64),
        _out("objective", objective, lead, np.float64),
        _out("wrench_residual", wrench_residual, lead, np.float64),
        _out("status", status, lead, np.int8),
    )


def _flat(outs: _Outputs, B: int, K: int, m: int) -> _Outputs:
    """The outputs as the native batch writes them: ``[B, K, m]`` and ``[B, K]`` views."""
    torque, objective, wrench_residual, status = outs
    return (
        torque.reshape((B, K, m)),
        objective.reshape((B, K)),
        wrench_residual.reshape((B, K)),
        status.reshape((B, K)),
    )


def _forces(given: Union[bool, Array, None], lead: Tuple[int, ...], n: int) -> Optional[Array]:
    """The contact forces' output: None unless asked for (True, or an array)."""
    if given is None or isinstance(given, bool):
        return _out("contact_forces", None, lead + (n,), np.float64) if given else None
    return _out("contact_forces", given, lead + (n,), np.float64)


def _threads(threads: Optional[int]) -> int:
    if threads is None:
        return _native.default_threads()
    return _count("threads", threads, 1, _native.MAX_THREADS)


def _errors(errors: Sequence[Tuple[int, int, str]], single: bool) -> BatchErrors:
    """``{b: message}`` for one wrench per grasp, else ``{(b, k): message}``."""
    return {g if single else (g, k): msg for g, k, msg in errors}


def solve_batch(
    G: ArrayLike,
    JT: ArrayLike,
    W: ArrayLike,
    contacts: Contacts,
    *,
    backend: Optional[str] = None,
    cones: str = "linear",
    sides: Optional[int] = None,
    latitudes: Optional[int] = None,
    sfce_spacing: Optional[str] = None,
    internal_forces: Optional[str] = None,
    paper_model: bool = False,
    torque_weights: Optional[ArrayLike] = None,
    torque_limits: Optional[TorqueLimits] = None,
    min_normal_force: Optional[MinNormalForce] = None,
    joint_names: Optional[Sequence[str]] = None,
    transmission: Optional[ArrayLike] = None,
    actuator_names: Optional[Sequence[str]] = None,
    passive_torque: Optional[ArrayLike] = None,
    threads: Optional[int] = None,
    warm_start: bool = True,
    torque: Optional[Array] = None,
    objective: Optional[Array] = None,
    wrench_residual: Optional[Array] = None,
    status: Optional[NDArray[np.int8]] = None,
    contact_forces: Union[bool, Array] = False,
) -> BatchResult:
    """Solves B grasps, each for one or K wrenches, in parallel, with the GIL released.

    ``G[B,6,n]`` and ``JT[B,m,n]`` are the grasps; ``W[B,6]`` gives one wrench per grasp
    and ``W[B,K,6]`` K of them (each grasp's model is built once and its wrenches are
    solved in order, each warm-started from the previous answer unless
    ``warm_start=False``). ``contacts``, the limits (``None`` or ``inf`` for a joint
    without one), weights and minimum normal forces are shared by every grasp. ``threads``
    defaults to one per core. A ``transmission`` T (``[m, a]`` shared, or ``[B, m, a]``
    per grasp, as a spatial tendon's moment arms change with the configuration) makes the
    outputs actuator forces u, ``torque[B,(K,)a]``, with the weights and limits per
    actuator. ``passive_torque`` (``[m]`` for every grasp or
    ``[B, m]``, one per row of JT) is the joints' passive torques, springs or the
    fingers' weight: then ``Jᵀ f = T u + passive_torque``.

    As in ``mujoco.rollout``, the outputs ``torque``, ``objective``,
    ``wrench_residual`` (float64) and ``status`` (int8) may be passed preallocated
    (C-contiguous, of the output shape) and are then filled in place.
    ``contact_forces=True`` (or such an array, ``[B,(K,)n]``) also returns the contact
    forces f. An invalid or infeasible item never raises: it gets its status code; only
    arguments that make the whole batch impossible (shapes, contacts, options) raise
    ``ValueError``. Ctrl-C stops the batch within about 50 ms (Python's signal handlers
    run between spans of grasps), with the spans before it written in the outputs.
    """
    g, jt = _real("G", G), _real("JT", JT)
    if g.ndim != 3:
        raise ValueError(f"G: expected shape (B, 6, n), got {g.shape}")
    if jt.ndim != 3:
        raise ValueError(f"JT: expected shape (B, m, n), got {jt.shape}")
    W3, single = _wrenches(_real("W", W), g.shape[0])
    B, K, m = g.shape[0], W3.shape[1], jt.shape[1]
    shared, per_grasp = None, None
    if transmission is not None:
        T = _real("transmission", transmission)
        if T.ndim == 2 and T.shape[0] == m:
            shared = T
        elif T.ndim == 3 and T.shape[:2] == (B, m):
            per_grasp = T
        else:
            raise ValueError(
                f"transmission: expected shape ({m}, a) or ({B}, {m}, a), one row per joint of JT, got {T.shape}"
            )
        m = T.shape[-1]
    passive = None
    if passive_torque is not None:
        tp = _real("passive_torque", passive_torque)
        if tp.ndim not in (1, 2) or tp.shape[-1] != jt.shape[1]:
            raise ValueError(
                f"passive_torque: expected shape ({jt.shape[1]},) or ({B}, {jt.shape[1]}), one per row of JT, got {tp.shape}"
            )
        passive = np.ascontiguousarray(np.broadcast_to(tp, (B, tp.shape[0])) if tp.ndim == 1 else tp)
    lead = (B,) if single else (B, K)
    outs = _outputs(lead, m, torque, objective, wrench_residual, status)
    F = _forces(contact_forces, lead, g.shape[2])
    _apart(
        dict(zip(_OUTPUT_NAMES, outs), contact_forces=F),
        {"G": g, "JT": jt, "W": W3, "passive_torque": passive, "transmission": per_grasp},
    )
    spec = {
        "contacts": _contacts(contacts),
        "torque_weights": torque_weights,
        "torque_limits": _limits(torque_limits),
        "min_normal_force": min_normal_force,
        "joint_names": None if joint_names is None else list(joint_names),
        "transmission": None if shared is None else shared.tolist(),
        "actuator_names": None if actuator_names is None else list(actuator_names),
    }
    settings = _settings(backend, cones, sides, latitudes, sfce_spacing, internal_forces, paper_model)
    errors = _native.solve_batch(
        g,
        jt,
        W3,
        passive,
        per_grasp,
        _dumps(spec),
        _dumps(settings),
        _threads(threads),
        bool(warm_start),
        *_flat(outs, B, K, m),
        None if F is None else F.reshape((B, K, g.shape[2])),
    )
    return BatchResult(*outs, _errors(errors, single), F)


class HandBatchResult(NamedTuple):
    """``BatchResult`` with ``names``: the joints (or, for an MJCF hand with
    actuators, the actuators) of ``torque``'s last axis, in order; ``contact_forces``
    (with ``contact_forces=True``) in the contacts' order."""

    torque: Array
    objective: Array
    wrench_residual: Array
    status: NDArray[np.int8]
    errors: BatchErrors
    names: List[str]
    contact_forces: Optional[Array] = None


class HandArrays(NamedTuple):
    """What ``Hand.arrays`` builds: ``G[B,6,n]`` and ``JT[B,m,n]`` per grasp
    (NaN for a rejected one), the transmission of an MJCF hand with actuators (else None):
    ``T[m,a]``, or ``T[B,m,a]`` per grasp when spatial tendons drive it (their moment arms
    change with the configuration), the names of JT's rows and T's columns, ``errors``:
    ``{b: message}``, and ``passive_torque[B,m]``: the springs' torques on JT's rows at
    each configuration (MuJoCo's ``qfrc_spring``), plus the links' weight with
    ``gravity``; zero for a hand without either. ``solve_batch`` takes it as
    ``passive_torque`` to solve what ``Hand.solve_batch`` solves. ``object_wrench[B,6]``,
    with ``object_mass``: what the object's weight asks of the contacts, in the object
    frame (add it to the wrenches), else None. ``torque_limits[a|m, 2]``: the model's
    limits (``torque_limits="model"``: URDF efforts, MJCF force ranges) on T's columns, or
    JT's rows without T, as ``[lower, upper]`` rows with ``∓inf`` where open; ``solve_batch``
    takes it as ``torque_limits``."""

    G: Array
    JT: Array
    transmission: Optional[Array]
    joint_names: List[str]
    actuator_names: Optional[List[str]]
    errors: Dict[int, str]
    passive_torque: Array
    object_wrench: Optional[Array]
    torque_limits: Array


def _object(object_mass: Optional[float], center_of_mass: Optional[ArrayLike]) -> Optional[Dict[str, Any]]:
    """The hand form's ``object``, from ``Hand``'s keywords."""
    if object_mass is None:
        if center_of_mass is not None:
            raise ValueError("center_of_mass: given without object_mass")
        return None
    if np.ndim(object_mass) != 0:
        raise ValueError(f"object_mass: expected one number, got shape {np.shape(object_mass)}")
    # (`_real` gives a 0-d value one dimension.)
    mass = _real("object_mass", object_mass).item()
    com = [0.0, 0.0, 0.0] if center_of_mass is None else _real("center_of_mass", center_of_mass)
    if np.shape(com) != (3,):
        raise ValueError(f"center_of_mass: expected [x, y, z], got shape {np.shape(com)}")
    return {"mass": mass, "center_of_mass": [float(c) for c in com]}


class Hand:
    """A robot hand from a URDF or MJCF file, parsed once per process: where a grasp
    planner that tries many configurations and contact points of one hand starts.

    ``Hand(path).solve_batch(joint_positions, W, contacts, positions=..., normals=...)``
    builds each grasp's G and Jᵀ from the hand's kinematics in Rust, in parallel with
    the GIL released, and solves it, as ``solve_batch`` does for arrays. The contacts
    are the hand form's (``docs/hands.md``), fixed for the batch: each names a ``link``
    or ``site``, with ``model``, ``mu``, ``mu_torsion`` and optionally ``frame``
    (``"object"`` or ``"link"``), ``position`` and ``normal``.
    """

    def __init__(self, path: Union[str, "os.PathLike[str]"]):
        self._path = os.fspath(path)
        self._native = _native.Hand(self._path)

    @property
    def name(self) -> str:
        """The robot's (or MJCF model's) name."""
        return self._native.name

    @property
    def joint_names(self) -> List[str]:
        """The independent joints (neither fixed nor mimic), in file order: the columns
        of ``joint_positions``."""
        return self._native.joint_names

    @property
    def links(self) -> List[str]:
        """The links (MJCF bodies), in file order."""
        return self._native.links

    @property
    def sites(self) -> List[str]:
        """The MJCF sites."""
        return self._native.sites

    @property
    def warnings(self) -> List[str]:
        """What reading the file ignored or found suspicious, one line each."""
        return self._native.warnings

    def __reduce__(self) -> Tuple[Any, Tuple[Any, ...]]:
        return (Hand, (self._path,))

    def __repr__(self) -> str:
        return repr(self._native)

    def _poses(
        self,
        joint_positions: ArrayLike,
        positions: Optional[ArrayLike],
        normals: Optional[ArrayLike],
        object_pose: Optional[ArrayLike],
    ) -> Tuple[Array, Optional[Array], Optional[Array], Optional[Array]]:
        """The per-grasp arrays, checked and made C-contiguous float64."""
        q = _real("joint_positions", joint_positions)
        if q.ndim != 2:
            raise ValueError(
                f"joint_positions: expected shape (B, {len(self.joint_names)}), got {q.shape}"
            )
        B = q.shape[0]
        arrays: Dict[str, Optional[Array]] = {}
        for name, given in (("positions", positions), ("normals", normals)):
            a = None if given is None else _real(name, given)
            if a is not None and a.ndim != 3:
                raise ValueError(f"{name}: expected shape (B, k, 3), got {a.shape}")
            arrays[name] = a
        pose = None
        if object_pose is not None:
            pose = _real("object_pose", object_pose)
            if pose.shape == (7,):
                pose = np.ascontiguousarray(np.broadcast_to(pose, (B, 7)))
            elif pose.ndim != 2:
                raise ValueError(
                    f"object_pose: expected shape (7,) or ({B}, 7), [x, y, z, qw, qx, qy, qz], got {pose.shape}"
                )
        return q, arrays["positions"], arrays["normals"], pose

    def frames(
        self, joint_positions: ArrayLike, names: Sequence[str], *, threads: Optional[int] = None
    ) -> Tuple[Array, Array]:
        """Where sites and links are: ``(positions, rotations)`` of the frames ``names``
        (MJCF sites, or links) at each configuration, in the model's root frame (a
        URDF's root link, an MJCF's world; ``object_pose`` is given in it).

        ``joint_positions`` is ``[B, len(joint_names)]`` (or one configuration,
        ``[len(joint_names)]``); ``positions`` is then ``[B, k, 3]`` and ``rotations``
        ``[B, k, 3, 3]``, whose columns are the frame's x, y and z axes (a site's z axis
        is a site contact's default normal), without the leading ``B`` for one
        configuration. A planner places the object and the contact points from them:
        the fingertip sites' centroid as the object's origin, say. The configurations are
        posed on ``threads`` threads (default: one per core) with the GIL released;
        Ctrl-C stops it between spans of about 50 ms.
        """
        q = _real("joint_positions", joint_positions)
        single = q.ndim == 1
        if single:
            q = q[None, :]
        if q.ndim != 2:
            raise ValueError(
                f"joint_positions: expected shape (B, {len(self.joint_names)}) or ({len(self.joint_names)},), got {q.shape}"
            )
        if isinstance(names, str):
            raise ValueError("names: expected a sequence of link or site names, got a string")
        frames = [str(n) for n in names]
        P = np.empty((q.shape[0], len(frames), 3))
        R = np.empty((q.shape[0], len(frames), 3, 3))
        self._native.frames(q, frames, P, R, _threads(threads))
        return (P[0], R[0]) if single else (P, R)

    def arrays(
        self,
        joint_positions: ArrayLike,
        contacts: Contacts,
        *,
        positions: Optional[ArrayLike] = None,
        normals: Optional[ArrayLike] = None,
        object_pose: Optional[ArrayLike] = None,
        gravity: Union[None, str, ArrayLike] = None,
        object_mass: Optional[float] = None,
        center_of_mass: Optional[ArrayLike] = None,
        threads: Optional[int] = None,
    ) -> HandArrays:
        """Each grasp's G, Jᵀ and passive torques (the springs', and the links' weight
        with ``gravity``), posed as ``solve_batch`` poses them (same arguments), for
        ``gt.solve_batch``, another solver or a grasp-quality measure. G's columns are the
        contacts' force components in their frames (``docs/geometry.md``), in the object
        frame about its origin; JT's rows are ``joint_names``. With ``object_mass`` (and
        ``gravity``), ``object_wrench`` is its weight's wrench on the contacts. The grasps
        are posed on ``threads`` threads (default: one per core) with the GIL released;
        Ctrl-C stops it between spans of about 50 ms."""
        q, P, N, pose = self._poses(joint_positions, positions, normals, object_pose)
        g, rows = _gravity(gravity, q.shape[0])
        held = _object(object_mass, center_of_mass)
        spec = {"contacts": _contacts(contacts), "gravity": g, "object": held}
        spec_json = _dumps(spec)
        d = json.loads(self._native.describe(_dumps(dict(spec, torque_limits="model"))))
        B, n, m = q.shape[0], d["force_dim"], len(d["joint_names"])
        G = np.empty((B, 6, n))
        JT = np.empty((B, m, n))
        TP = np.empty((B, m))
        T = None if d["transmission"] is None else np.array(d["transmission"], dtype=np.float64)
        T3 = np.empty((B,) + T.shape) if T is not None and d["transmission_varies"] else None
        OW = None if held is None else np.empty((B, 6))
        errors = self._native.arrays(q, P, N, pose, rows, spec_json, _threads(threads), G, JT, TP, T3, OW)
        limits = np.full((len(d["torque_limits"]), 2), [-np.inf, np.inf])
        for j, lim in enumerate(d["torque_limits"]):
            if isinstance(lim, list):
                limits[j] = [-np.inf if lim[0] is None else lim[0], np.inf if lim[1] is None else lim[1]]
            elif lim is not None:
                limits[j] = [-lim, lim]
        return HandArrays(
            G,
            JT,
            T if T3 is None else T3,
            d["joint_names"],
            d["actuator_names"],
            dict(errors),
            TP,
            OW,
            limits,
        )

    def solve_batch(
        self,
        joint_positions: ArrayLike,
        W: Optional[ArrayLike],
        contacts: Contacts,
        *,
        positions: Optional[ArrayLike] = None,
        normals: Optional[ArrayLike] = None,
        object_pose: Optional[ArrayLike] = None,
        gravity: Union[None, str, ArrayLike] = None,
        object_mass: Optional[float] = None,
        center_of_mass: Optional[ArrayLike] = None,
        backend: Optional[str] = None,
        cones: str = "linear",
        sides: Optional[int] = None,
        latitudes: Optional[int] = None,
        sfce_spacing: Optional[str] = None,
        internal_forces: Optional[str] = None,
        paper_model: bool = False,
        torque_weights: Optional[ArrayLike] = None,
        torque_limits: Optional[TorqueLimits] = None,
        min_normal_force: Optional[MinNormalForce] = None,
        threads: Optional[int] = None,
        warm_start: bool = True,
        torque: Optional[Array] = None,
        objective: Optional[Array] = None,
        wrench_residual: Optional[Array] = None,
        status: Optional[NDArray[np.int8]] = None,
        contact_forces: Union[bool, Array] = False,
    ) -> HandBatchResult:
        """Solves B grasps of this hand, each for one or K wrenches, in parallel.

        Grasp b is the hand at ``joint_positions[b]`` (``[B, len(joint_names)]``,
        radians or metres; MuJoCo's ``qpos`` for an MJCF hand), its contacts at
        ``positions[b]`` with normals ``normals[b]`` (``[B, k, 3]``, each in its
        contact's ``frame``; a row of NaN, or no array, takes the contact dict's own, or
        the site's), and the object frame at ``object_pose`` (``[7]`` for every grasp or
        ``[B, 7]``, ``[x, y, z, qw, qx, qy, qz]`` in the root link's frame; default the
        root frame). ``W`` is ``[B, 6]`` or ``[B, K, 6]`` in the object frame: what the
        contacts must apply to the object.

        Every grasp has the same joints: the independent joints that move a contact's
        link (and those an actuator on them drives). ``names`` lists them, the last axis
        of ``torque``; an MJCF hand with actuators gives actuator forces.
        ``torque_limits="model"`` takes the file's limits. ``gravity`` (``[gx, gy,
        gz]`` in the root frame for every grasp, ``[B, 3]`` per grasp for a hand turned
        differently in each, or ``"model"``: an MJCF file's ``<option gravity>``) adds
        the links' weight to the springs' torques (default: weightless fingers).
        ``object_mass`` (with ``center_of_mass``, ``[x, y, z]`` in the object frame,
        default its origin) also weighs the object under that gravity, in each grasp's
        object pose: ``W`` is then what the contacts apply besides (``None``: nothing
        besides). The solver keywords,
        ``threads``, ``warm_start``, the preallocated outputs and ``contact_forces`` are
        ``solve_batch``'s.
        A grasp whose input is rejected (a NaN joint position, a normal that is not
        unit) is an ``invalid`` item with its message in ``errors``; only arguments that
        make the whole batch impossible raise ``ValueError``.
        """
        q, P, N, object_pose = self._poses(joint_positions, positions, normals, object_pose)
        held = _object(object_mass, center_of_mass)
        if W is None:
            if held is None:
                raise ValueError("W: expected [B, 6] or [B, K, 6] wrenches (None only with object_mass)")
            W = np.zeros((q.shape[0], 6))
        W3, single = _wrenches(_real("W", W), q.shape[0])
        B, K = q.shape[0], W3.shape[1]
        spec = {
            "contacts": _contacts(contacts),
            "gravity": None,
            "object": held,
            "torque_weights": torque_weights,
            "torque_limits": _limits(torque_limits),
            "min_normal_force": min_normal_force,
        }
        settings = _settings(
            backend, cones, sides, latitudes, sfce_spacing, internal_forces, paper_model
        )
        spec["gravity"], rows = _gravity(gravity, B)
        spec_json, settings_json = _dumps(spec), _dumps(settings)
        names, _, n = self._native.layout(spec_json, settings_json)
        m = len(names)
        lead = (B,) if single else (B, K)
        outs = _outputs(lead, m, torque, objective, wrench_residual, status)
        F = _forces(contact_forces, lead, n)
        _apart(
            dict(zip(_OUTPUT_NAMES, outs), contact_forces=F),
            {"joint_positions": q, "W": W3, "positions": P, "normals": N, "object_pose": object_pose},
        )
        errors = self._native.solve_batch(
            q,
            W3,
            P,
            N,
            object_pose,
            rows,
            spec_json,
            settings_json,
            _threads(threads),
            bool(warm_start),
            *_flat(outs, B, K, m),
            None if F is None else F.reshape((B, K, n)),
        )
        return HandBatchResult(*outs, _errors(errors, single), list(names), F)


# 2³¹ float64 numbers (16 GiB) in the arrays `synthetic_grasps` returns, at most.
_MAX_SYNTHETIC_NUMBERS = 1 << 31


def synthetic_grasps(
    batch: int,
    fingers: int = 3,
    joints_per_finger: int = 3,
    wrenches: int = 0,
    seed: int = 0,
) -> Tuple[Array, Array, Array]:
    """Random but physically sensible fingertip grasps of a sphere, for trying things
    and benchmarks: ``(G[B,6,n], JT[B,m,n], W[B,6] or W[B,K,6])`` with point contacts
    (``n = 3·fingers``, contact frames with z along the inward normal), serial fingers
    of revolute joints, and the sphere's weight (50–500 g) plus a small disturbance.
    ``wrenches=K > 0`` adds K load directions per grasp (± 10 % of the weight along
    each axis, cycling). A hand past the solver's limits (256 contacts, 256 joints) or
    arrays of more than 2³¹ numbers in all raise ``ValueError`` naming the argument."""
    # No larger hand can be solved, and no larger batch held in memory.
    fingers = _count("fingers", fingers, 1, _native.MAX_CONTACTS)
    joints_per_finger = _count(
        "joints_per_finger", joints_per_finger, 1, _native.MAX_JOINTS // fingers
    )
    wrenches = _count("wrenches", wrenches, 0, _MAX_SYNTHETIC_NUMBERS)
    n, m = 3 * fingers, fingers * joints_per_finger
    per_grasp = (6 + m) * n + 6 * max(wrenches, 1)
    batch = _count("batch", batch, 0, _MAX_SYNTHETIC_NUMBERS // per_grasp)
    rng = np.random.default_rng(seed)
    G = np.zeros((batch, 6, n))
    JT = np.zeros((batch, m, n))
    radius = rng.uniform(0.03, 0.06, batch)
    base_angle = rng.uniform(0, 2 * np.pi, batch)
    for f in range(fingers):
        # Contacts spread around the equator, jittered, a little below it.
        ang = base_angle + 2 * np.pi * f / fingers + rng.uniform(-0.3, 0.3, batch)
        elev = rng.uniform(-0.5, 0.2, batch)
        out = np.stack([np.cos(ang) * np.cos(elev), np.sin(ang) * np.cos(elev), np.sin(elev)], -1)
        p = out * radius[:, None]
        z = -out  # the contact normal points into the object
        helper = np.where(np.abs(z[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
        x = np.cross(helper, z)
        x /= np.linalg.norm(x, axis=1, keepdims=True)
        y = np.cross(z, x)
        R = np.stack([x, y, z], -1)  # columns: contact frame axes in the object frame
        cols = slice(3 * f, 3 * f + 3)
        G[:, :3, cols] = R
        G[:, 3:, cols] = np.cross(p[:, :, None], R, axisa=1, axisb=1, axisc=1)
        # The finger: joints from its base outside the sphere towards the contact.
        base = out * (radius[:, None] + 0.08) + rng.normal(0, 0.01, (batch, 3))
        tangent = np.cross(out, [[0.0, 0.0, 1.0]])
        tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-9)
        for j in range(joints_per_finger):
            t = j / joints_per_finger
            # A bent finger: joints off the straight line to the contact, so that the
            # finger's levers span all three directions (a straight one is singular).
            q = base + (p - base) * t + (j > 0) * rng.normal(0, 0.015, (batch, 3))
            axis = tangent if j > 0 else np.cross(tangent, out)
            axis = axis + rng.normal(0, 0.1, (batch, 3))
            axis /= np.linalg.norm(axis, axis=1, keepdims=True)
            lever = np.cross(axis, p - q)  # τ = (a × (p − q)) · f_object
            JT[:, f * joints_per_finger + j, cols] = np.einsum("bi,bij->bj", lever, R)
    mass = rng.uniform(0.05, 0.5, batch)
    W = np.zeros((batch, 6))
    W[:, 2] = mass * 9.81  # the contacts push the object up against gravity
    W[:, :3] += rng.normal(0, 0.05, (batch, 3)) * mass[:, None]
    if wrenches:
        Wk = np.repeat(W[:, None, :], wrenches, axis=1)
        for k in range(wrenches):
            component, sign = (k // 2) % 3, 1.0 if k % 2 == 0 else -1.0
            Wk[:, k, component] += sign * 0.1 * mass * 9.81
        return G, JT, Wk
    return G, JT, W
