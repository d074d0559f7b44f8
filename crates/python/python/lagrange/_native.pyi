# Types of the native half, `lagrange._native` (crates/python/src): what mypy and editors see
# of the compiled module. tests/test_lagrange.py holds it to the module's names.

from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

# The settings of a run, as lagrange._run_options makes them: every key of simulate's keyword
# arguments (until, method, tolerance, step, output, set, input, input_series, hold,
# stop_when, events, samples), None or empty for the scene's setting.
RunOptions = Mapping[str, Any]

# Parameter values: a mapping of name to value, or an array of every value in order.
Parameters = Union[Mapping[str, float], npt.ArrayLike]
# Input values: a mapping of name to a number, an array of one value per row of a batch, or a
# callable of (t, y); or an array of every input's value in order.
Inputs = Union[Mapping[str, Any], npt.ArrayLike]

class NativeScene:
    @property
    def warnings(self) -> str: ...
    @property
    def title(self) -> Optional[str]: ...
    @property
    def source(self) -> str: ...
    @property
    def path(self) -> str: ...
    @property
    def units(self) -> bool: ...
    def derive(self) -> dict[str, Any]: ...
    def rhs(self) -> Rhs: ...
    def mass_matrix_function(self) -> MassMatrix: ...
    def inverse_dynamics(self) -> InverseDynamics: ...
    def simulate(self, options: RunOptions) -> dict[str, Any]: ...
    def batch(
        self,
        names: Sequence[str],
        values: npt.NDArray[np.float64],
        threads: int,
        options: RunOptions,
    ) -> dict[str, Any]: ...
    def ensemble(
        self,
        vary: Sequence[str],
        runs: Optional[int],
        seed: int,
        record: Sequence[str],
        threads: Optional[int],
        start: int,
        stop: Optional[int],
        options: RunOptions,
    ) -> dict[str, Any]: ...
    def linearize(
        self,
        about: Optional[str] = None,
        set: Sequence[str] = ...,
        sweep: Optional[str] = None,
        keep_cyclic: bool = True,
    ) -> dict[str, Any]: ...
    def linearize_along(
        self,
        options: RunOptions,
        times: Optional[Sequence[float]] = None,
        states: Optional[Sequence[Sequence[float]]] = None,
        inputs: Optional[Sequence[Sequence[float]]] = None,
    ) -> dict[str, Any]: ...
    def orbit(
        self,
        period: Optional[str] = None,
        section: Optional[str] = None,
        direction: str = "rising",
        shift: Sequence[str] = ...,
        swap: Sequence[str] = ...,
        ignore: Sequence[str] = ...,
        set: Sequence[str] = ...,
        until: Optional[float] = None,
        method: Optional[str] = None,
        tolerance: Optional[float] = None,
        iterations: int = 30,
    ) -> dict[str, Any]: ...
    def fit(
        self,
        data: str,
        free: str,
        options: dict[str, Any],
        noise: Sequence[tuple[str, float]] = ...,
        bounds: Sequence[str] = ...,
        shots: int = 1,
        iterations: int = 100,
    ) -> dict[str, Any]: ...
    def check(self) -> list[dict[str, Any]]: ...

class Rhs:
    """y' = F(t, y) of a scene for ``scipy.integrate.solve_ivp``."""

    names: list[str]
    parameter_names: list[str]
    derived_parameter_names: list[str]
    input_names: list[str]
    @property
    def y0(self) -> npt.NDArray[np.float64]: ...
    @property
    def inputs(self) -> Mapping[str, float]: ...
    @property
    def parameters(self) -> Mapping[str, float]: ...
    @parameters.setter
    def parameters(self, p: Parameters) -> None: ...
    @property
    def derived_parameters(self) -> Mapping[str, float]: ...
    def __call__(
        self,
        t: float,
        y: npt.ArrayLike,
        p: Optional[Parameters] = None,
        u: Optional[Inputs] = None,
    ) -> npt.NDArray[np.float64]: ...
    def batch(
        self,
        y: npt.ArrayLike,
        t: Union[None, float, npt.ArrayLike] = None,
        p: Optional[Parameters] = None,
        u: Optional[Inputs] = None,
    ) -> npt.NDArray[np.float64]: ...
    def jac(
        self,
        t: float,
        y: npt.ArrayLike,
        p: Optional[Parameters] = None,
        u: Optional[Inputs] = None,
    ) -> npt.NDArray[np.float64]: ...

class InverseDynamics:
    """τ = M·q̈ − f of a scene over many motions."""

    names: list[str]
    parameter_names: list[str]
    derived_parameter_names: list[str]
    input_names: list[str]
    kept_constraints: list[str]
    @property
    def parameters(self) -> Mapping[str, float]: ...
    @parameters.setter
    def parameters(self, p: Parameters) -> None: ...
    @property
    def derived_parameters(self) -> Mapping[str, float]: ...
    def batch(
        self,
        t: npt.ArrayLike,
        q: npt.ArrayLike,
        qd: npt.ArrayLike,
        qdd: npt.ArrayLike,
        p: Optional[Parameters] = None,
        u: Optional[Inputs] = None,
    ) -> npt.NDArray[np.float64]: ...

class MassMatrix:
    """M(t, q) of a scene at its parameters' values."""

    names: list[str]
    def __call__(self, t: float, q: npt.ArrayLike) -> npt.NDArray[np.float64]: ...

def loads(text: str, path: str = "<string>", units: bool = True) -> NativeScene: ...
