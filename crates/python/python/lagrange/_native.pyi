# Types of the native half, `lagrange._native` (crates/python/src): what mypy and editors see
# of the compiled module. tests/test_lagrange.py holds it to the module's names.

from typing import Any, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

class NativeScene:
    @property
    def warnings(self) -> str: ...
    @property
    def title(self) -> Optional[str]: ...
    @property
    def source(self) -> str: ...
    @property
    def path(self) -> str: ...
    def derive(self) -> dict[str, Any]: ...
    def rhs(self) -> Rhs: ...
    def mass_matrix_function(self) -> MassMatrix: ...
    def simulate(
        self,
        until: Optional[float] = None,
        method: Optional[str] = None,
        tolerance: Optional[float] = None,
        step: Optional[float] = None,
        output: Sequence[str] = ...,
        set: Sequence[str] = ...,
        stop_when: Sequence[str] = ...,
        events: Sequence[str] = ...,
        samples: int = 0,
    ) -> dict[str, Any]: ...
    def linearize(
        self,
        about: Optional[str] = None,
        set: Sequence[str] = ...,
        sweep: Optional[str] = None,
        keep_cyclic: bool = True,
    ) -> dict[str, Any]: ...
    def check(self) -> list[dict[str, Any]]: ...

class Rhs:
    """y' = F(t, y) of a scene for ``scipy.integrate.solve_ivp``."""

    names: list[str]
    @property
    def y0(self) -> npt.NDArray[np.float64]: ...
    @property
    def parameters(self) -> dict[str, float]: ...
    def __call__(self, t: float, y: npt.ArrayLike) -> npt.NDArray[np.float64]: ...
    def batch(
        self, y: npt.ArrayLike, t: Union[None, float, npt.ArrayLike] = None
    ) -> npt.NDArray[np.float64]: ...

class MassMatrix:
    """M(t, q) of a scene at its parameters' values."""

    names: list[str]
    def __call__(self, t: float, q: npt.ArrayLike) -> npt.NDArray[np.float64]: ...

def loads(text: str, path: str = "<string>", units: bool = True) -> NativeScene: ...
