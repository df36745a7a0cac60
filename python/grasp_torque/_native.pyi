# Types of the PyO3 extension (python/src/lib.rs). The public API is in __init__.py;
# of these classes, users meet `Result` directly. `python -m mypy.stubtest
# grasp_torque._native` checks this file against the built module (.ci/run).
from typing import Any, Optional, final

import numpy as np
import numpy.typing as npt

__all__ = ["Problem", "Solver", "Result", "Hand", "solve_batch", "default_threads", "backends", "INVALID", "MAX_THREADS", "MAX_JOINTS", "MAX_CONTACTS", "VERSION"]

_F64 = npt.NDArray[np.float64]
_I8 = npt.NDArray[np.int8]

INVALID: int
MAX_THREADS: int
MAX_JOINTS: int
MAX_CONTACTS: int
VERSION: str

def backends() -> list[str]: ...
def default_threads() -> int: ...
def solve_batch(
    g: _F64,
    jt: _F64,
    w: _F64,
    passive: Optional[_F64],
    transmissions: Optional[_F64],
    spec_json: str,
    settings_json: str,
    threads: int,
    warm_start: bool,
    torque: _F64,
    objective: _F64,
    wrench_residual: _F64,
    status: _I8,
    forces: Optional[_F64],
) -> list[tuple[int, int, str]]: ...

@final
class Problem:
    @staticmethod
    def from_json(text: str, base: str, hand: Optional[str] = None) -> Problem: ...
    def to_json(self) -> str: ...
    def hand_json(self) -> Optional[str]: ...
    @property
    def joints(self) -> int: ...
    @property
    def force_dim(self) -> int: ...
    @property
    def contacts(self) -> int: ...
    @property
    def joint_names(self) -> Optional[list[str]]: ...
    @property
    def wrench(self) -> _F64: ...
    @property
    def grasp_matrix(self) -> _F64: ...
    @property
    def jacobian_transpose(self) -> _F64: ...
    @property
    def passive_torque(self) -> Optional[_F64]: ...
    def __reduce__(self) -> Any: ...

@final
class Solver:
    def __new__(cls, problem: Problem, settings_json: str) -> Solver: ...
    def solve(self, wrench: Optional[list[float]] = None, warm: bool = True) -> Result: ...
    def diagnose(self) -> Result: ...
    def problem(self) -> Problem: ...
    def settings_json(self) -> str: ...
    @property
    def backend(self) -> str: ...
    def __reduce__(self) -> Any: ...

@final
class Result:
    """One solve's answer: its status, torque, forces, objective and checks."""

    @staticmethod
    def from_json(text: str) -> Result: ...
    def to_json(self) -> str: ...
    def to_dict(self) -> dict[str, Any]: ...
    def reason_json(self) -> Optional[str]: ...
    def __reduce__(self) -> Any: ...
    @property
    def status(self) -> str:
        """``optimal``, ``almost_optimal``, ``infeasible``, ``iteration_limit`` or
        ``numerical_failure``."""
    @property
    def reason(self) -> Optional[str]:
        """Why it is not optimal, as the command line says it."""
    @property
    def reason_detail(self) -> Optional[dict[str, Any]]:
        """The reason's ``kind`` and fields."""
    @property
    def torque(self) -> Optional[_F64]:
        """τ per joint, or u per actuator with a transmission."""
    @property
    def joint_torque(self) -> Optional[_F64]:
        """τ per joint (T u with a transmission)."""
    @property
    def contact_forces(self) -> Optional[_F64]:
        """f, each contact's components in its frame, in contact order."""
    @property
    def forces_per_contact(self) -> Optional[list[_F64]]: ...
    @property
    def object_forces(self) -> Optional[_F64]:
        """``[k, 3]``: each contact's force on the object, in the wrench frame."""
    @property
    def contact_dims(self) -> list[int]: ...
    @property
    def objective(self) -> Optional[float]:
        """σ = Σ w_j τ_j²."""
    @property
    def residuals(self) -> Optional[dict[str, float]]:
        """``wrench`` ‖G f − w‖∞, ``torque`` ‖Jᵀ f − τ‖∞, ``consistency`` ‖C τ − e‖∞."""
    @property
    def diagnostics(self) -> dict[str, Any]: ...
    @property
    def iterations(self) -> int: ...
    @property
    def active_set(self) -> Optional[list[int]]: ...
    @property
    def solve_time_us(self) -> float: ...
    @property
    def joint_names(self) -> Optional[list[str]]: ...
    @property
    def actuator_names(self) -> Optional[list[str]]: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def backend(self) -> str: ...
    @property
    def cones(self) -> str: ...

@final
class Hand:
    def __new__(cls, path: str) -> Hand: ...
    @property
    def name(self) -> str: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def links(self) -> list[str]: ...
    @property
    def sites(self) -> list[str]: ...
    @property
    def warnings(self) -> list[str]: ...
    def layout(self, spec_json: str, settings_json: str) -> tuple[list[str], bool, int]: ...
    def describe(self, spec_json: str) -> str: ...
    def solve_batch(
        self,
        q: _F64,
        w: _F64,
        positions: Optional[_F64],
        normals: Optional[_F64],
        poses: Optional[_F64],
        gravity: Optional[_F64],
        spec_json: str,
        settings_json: str,
        threads: int,
        warm_start: bool,
        torque: _F64,
        objective: _F64,
        wrench_residual: _F64,
        status: _I8,
        forces: Optional[_F64],
    ) -> list[tuple[int, int, str]]: ...
    def arrays(
        self,
        q: _F64,
        positions: Optional[_F64],
        normals: Optional[_F64],
        poses: Optional[_F64],
        gravity: Optional[_F64],
        spec_json: str,
        threads: int,
        g: _F64,
        jt: _F64,
        tp: _F64,
        tr: Optional[_F64],
        ow: Optional[_F64],
    ) -> list[tuple[int, str]]: ...
    def frames(self, q: _F64, names: list[str], pos: _F64, rot: _F64, threads: int) -> None: ...
    def __reduce__(self) -> Any: ...
