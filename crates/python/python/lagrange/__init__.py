"""Lagrangian mechanics from scene files, in Python.

``lagrange`` reads a scene (``.lag``) file, derives its Euler–Lagrange equations exactly and
hands them to Python: the equations, mass matrix and reactions as SymPy expressions, the
equations of motion as a fast callable for ``scipy.integrate.solve_ivp`` and NumPy, and its
own simulations as NumPy arrays::

    import lagrange
    scene = lagrange.load("examples/ps5/falling_rod.lag")
    d = scene.derive()
    d.mass_matrix                 # a sympy.Matrix
    d.at_start["theta''"]         # 12*g/(7*L), exactly
    f = scene.rhs()               # f(t, y) for solve_ivp, y = coordinates then rates
    scene.inverse_dynamics(t, q, qd, qdd)   # the generalized forces of a motion
    run = scene.simulate(until=1.0)
    run["theta"], run["t"]        # NumPy arrays

In a notebook a derivation shows its equations (``_repr_latex_``). Mistakes in a scene raise
:class:`SceneError` with the file, line and column and the diagnostic as the ``lagrange``
command prints it.
"""

from collections.abc import Mapping
from dataclasses import dataclass, field
from fractions import Fraction
import math
import numbers
import os

from importlib import metadata as _metadata

# NumPy comes with the package: imported here once, rather than on a first call that may run
# on a worker thread (where a first import holds the import lock) or inside a timed loop.
import numpy

from . import _native
from ._errors import NumericError, SceneError
from ._native import InverseDynamics, MassMatrix, Rhs

__all__ = [
    "load",
    "loads",
    "Scene",
    "Derivation",
    "Constraint",
    "Expectation",
    "Linearization",
    "LinearizationAlong",
    "Orbit",
    "Fit",
    "Results",
    "ContactEvents",
    "Batch",
    "EnsembleTable",
    "Rhs",
    "MassMatrix",
    "InverseDynamics",
    "SceneError",
    "NumericError",
    "__version__",
]

try:
    # The installed distribution's version, which maturin takes from the crate's.
    __version__ = _metadata.version("lagrange")
except _metadata.PackageNotFoundError:  # pragma: no cover - run from a source tree
    __version__ = "0+unknown"


def load(path, *, units=True):
    """Loads the scene file at ``path`` (a ``str`` or ``os.PathLike``) and derives it.

    ``units=False`` skips the dimension check (as ``--no-units`` does). Raises
    :class:`SceneError` when the scene has mistakes, ``OSError`` when the file cannot be read.
    """
    path = os.fspath(path)
    with open(path, encoding="utf-8") as f:
        text = f.read()
    return Scene(_native.loads(text, path, units))


def loads(text, *, name="<string>", units=True):
    """Loads a scene from its text; ``name`` stands for the file in diagnostics."""
    return Scene(_native.loads(text, name, units))


def _scene_from(text, name, units):
    """A :class:`Scene` made again from its pickle."""
    return Scene(_native.loads(text, name, units))


def _listed(value):
    """``None``, one string or a sequence of them, as a list of strings."""
    if value is None:
        return []
    if isinstance(value, str):
        return [value]
    return [str(v) for v in value]


def _run_options(
    until=None,
    method=None,
    tolerance=None,
    output=None,
    set=None,
    step=None,
    input=None,
    hold=None,
    stop_when=None,
    events=None,
    samples=0,
):
    """The keyword arguments of the native ``simulate`` and ``batch``, checked: the settings
    :meth:`Scene.simulate` takes."""
    if isinstance(samples, bool) or not isinstance(samples, numbers.Integral):
        raise TypeError(f"`samples` must be a whole number, not {samples!r}")
    if samples < 0:
        raise ValueError(f"`samples` must be 0 (every step) or a positive count, not {samples}")
    laws, series = _inputs(input)
    return dict(
        until=_number("until", until),
        method=method,
        tolerance=_number("tolerance", tolerance),
        step=_number("step", step),
        output=_listed(output),
        set=_assignments(set),
        input=laws,
        input_series=series,
        hold=_number("hold", hold),
        stop_when=_listed(stop_when),
        events=_listed(events),
        samples=int(samples),
    )


def _number(name, value):
    """A setting's number, or ``None`` left as it is: a bool is refused rather than read as 0
    or 1 (``until=True`` is a mistake, not a run to t = 1)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"`{name}` must be a number, not {value!r}")
    return float(value)


def _count(name, value):
    """A whole number of values (a grid axis's, a sweep's): 3.0 is 3, 2.9 is refused rather than
    cut to 2."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"`{name}` must be a whole number of values, not {value!r}")
    if not float(value).is_integer():
        raise ValueError(f"`{name}` must be a whole number of values, not {value!r}")
    return int(value)


def _assignments(set):
    """``set`` as ``name=value`` texts: from a dict of name to value (a number or a scene
    expression), or texts already of that form, one string or a list of them."""
    if set is None:
        return []
    if isinstance(set, str):
        return [set]
    if isinstance(set, dict):
        return [f"{name}={_value_text(value)}" for name, value in set.items()]
    return [str(item) for item in set]


def _inputs(given):
    """``input`` as laws (``name=value`` texts) and time series (name, times, values): a dict
    of name to a law, or to a pair ``(times, values)`` of equal-length sequences."""
    if not isinstance(given, dict):
        return _assignments(given), []
    laws, series = {}, []
    for name, value in given.items():
        if isinstance(value, (tuple, list)) and len(value) == 2 and not isinstance(value[0], str):
            times, values = value
            series.append((str(name), [float(t) for t in times], [float(v) for v in values]))
        else:
            laws[name] = value
    return _assignments(laws), series


def _sweep_text(sweep):
    """``sweep`` as ``p=a:b:n``: a text of that form, or a dict of one parameter to
    ``(a, b, n)``."""
    if not isinstance(sweep, dict):
        return sweep
    if len(sweep) != 1:
        raise ValueError(f"a sweep takes one parameter, not {len(sweep)}")
    ((name, ends),) = sweep.items()
    a, b, n = ends
    return f"{name}={float(a)!r}:{float(b)!r}:{_count(name, n)}"


def _value_text(value):
    """A ``set`` value as scene text: numbers exactly (0.1 is 1/10), strings as written."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        raise TypeError("a set value is a number or a scene expression, not a bool")
    if isinstance(value, int):
        return str(value)
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"a set value must be finite, not {value}")
    text = repr(value)
    if "e" in text or "E" in text:
        q = Fraction(value)
        return f"{q.numerator}/{q.denominator}" if q.denominator != 1 else str(q.numerator)
    return text


def _vary_texts(vary):
    """``vary`` as ``--vary`` texts: from a dict of name to ``(a, b, n)`` or to a
    distribution's text, or texts already of that form."""
    if isinstance(vary, str):
        return [vary]
    if not isinstance(vary, Mapping):
        return [str(v) for v in vary]
    texts = []
    for name, spread in vary.items():
        if isinstance(spread, str):
            texts.append(f"{name}={spread}")
        else:
            a, b, n = spread
            texts.append(f"{name}={float(a)!r}:{float(b)!r}:{_count(name, n)}")
    return texts


def _batch_values(values, names):
    """The names and the 2-D array of a batch's values, from any of the forms
    :meth:`Scene.batch` takes."""
    if isinstance(values, Mapping):
        if names is not None:
            raise TypeError("names come from the dict's keys; leave `names` out")
        names = [str(k) for k in values]
        columns = [numpy.asarray(values[k], dtype=float).reshape(-1) for k in values]
        lengths = {len(c) for c in columns}
        if len(lengths) > 1:
            raise ValueError(f"every name needs as many values; got {sorted(lengths)}")
        rows = numpy.stack(columns, axis=1) if columns else numpy.zeros((0, 0))
        return names, numpy.ascontiguousarray(rows)
    if names is None:
        values = list(values)
        if not all(isinstance(v, Mapping) for v in values):
            raise TypeError("give `names` with a 2-D array of values, or a list of dicts")
        names = list(dict.fromkeys(str(k) for v in values for k in v))
        missing = [k for v in values for k in names if k not in v]
        if missing:
            raise ValueError(f"every run needs a value of each name; one lacks {missing[0]!r}")
        rows = numpy.array([[float(v[k]) for k in names] for v in values], dtype=float)
        return names, rows.reshape(len(values), len(names))
    names = [names] if isinstance(names, str) else [str(n) for n in names]
    rows = numpy.asarray(values, dtype=float)
    if rows.ndim == 1 and len(names) == 1:
        rows = rows.reshape(-1, 1)
    if rows.ndim != 2 or rows.shape[1] != len(names):
        raise ValueError(
            f"`values` needs a row a run and a column for each of {len(names)} names, "
            f"not shape {rows.shape}"
        )
    return names, numpy.ascontiguousarray(rows)


class Scene:
    """A loaded scene: parsed, resolved and derived. Made by :func:`load` or :func:`loads`.

    A scene may be shared between threads: its runs release the GIL and run side by side.
    It pickles as its text and settings (``multiprocessing``, ``concurrent.futures``' process
    pools and Dask send it so), and is loaded again where it is unpickled.
    """

    def __init__(self, native):
        self._native = native
        self._derivation = None
        self._inverse = None

    def __reduce__(self):
        return (_scene_from, (self._native.source, self._native.path, self._native.units))

    @property
    def title(self):
        """The scene's title, or ``None``."""
        return self._native.title

    @property
    def path(self):
        """The file name the scene goes by in diagnostics."""
        return self._native.path

    @property
    def source(self):
        """The scene's text."""
        return self._native.source

    @property
    def warnings(self):
        """The warnings met while loading, rendered as the ``lagrange`` command prints them
        (``""`` when there are none)."""
        return self._native.warnings

    def derive(self):
        """The derivation as SymPy objects: a :class:`Derivation` (computed once)."""
        if self._derivation is None:
            self._derivation = Derivation(self._native.derive(), scene=self)
        return self._derivation

    def rhs(self):
        """y' = f(t, y) of the equations of motion, for ``scipy.integrate.solve_ivp``.

        The state y holds the remaining coordinates, then their rates (``f.names`` lists
        them; ``f.y0`` is the scene's initial state). ``f(t, y)`` returns the 1-D array
        (q̇, q̈); ``f.batch(Y, t=0.0)`` evaluates every row of the 2-D array ``Y`` in one call
        (``t`` one time, or one per row). The scene's lowered programs compute it at the
        parameters' values (``f.parameters``), solving for constraint multipliers as
        :meth:`simulate` does. ``f.jac(t, y)`` is the exact Jacobian ∂f/∂y, an n×n array,
        for ``solve_ivp(f, ..., method="Radau", jac=f.jac)`` (also BDF and LSODA); its
        partials are derived and lowered on the first call. A singular mass matrix raises
        :class:`NumericError`.

        Parameter values: ``f(t, y, p=…)`` and ``f.batch(Y, t, p=…)`` take them for that call
        only, as an array in the order of ``f.parameter_names`` or a dict of name to value
        (the values it does not name stay); ``solve_ivp(f, …, args=(p,))`` passes them.
        The scene's inputs are not parameters (``f.parameter_names`` leaves them out, as
        :meth:`Derivation.parameter_values` does): ``u=`` gives them, for that call, as a dict
        of input name to a number, to a callable ``law(t, y)`` returning a number (a feedback
        law or a signal of time), or in ``batch`` to an array of one value per row; or as an
        array in the order of ``f.input_names``. An input ``u`` does not name takes its
        declared value (``f.inputs``). ``solve_ivp(f, …, args=(None, u), jac=f.jac)`` hands
        ``u`` to both. ``f.jac(t, y, u=…)`` is exact for numbers; an input a callable gives
        adds ∂f/∂u·∂u/∂y, both by central differences (a callable has no exact derivative).
        ``f.parameters = {"g": 1.62}`` (or an array) changes them for every later call.
        ``f.parameters`` itself is a read-only mapping: assigning to an item of it raises
        ``TypeError`` rather than changing a copy that nothing reads. A parameter the scene
        defines from others (``param I = m*L^2/12``) is derived: ``f.parameter_names`` and
        ``f.parameters`` leave it out, ``f.derived_parameter_names`` and the read-only
        ``f.derived_parameters`` list it, it follows the parameters it names whenever they
        change (as ``simulate(set=…)`` has it follow), and giving it a value raises
        ``ValueError`` naming them.
        """
        return self._native.rhs()

    def inverse_dynamics(self, t, q, qd, qdd, p=None, u=None):
        """The generalized forces τ = M(q)·q̈ − f(q, q̇, t) that make the scene move with
        positions ``q``, rates ``qd`` and accelerations ``qdd`` at time ``t``: added to the
        scene's own forces (M·q̈ = f + τ), they reproduce the motion (computed-torque control,
        actuator sizing).

        One motion: ``t`` a number and ``q``, ``qd``, ``qdd`` 1-D arrays of the remaining
        coordinates (``Derivation.coordinates``' order), giving a 1-D array. Many: ``t`` one
        time per row (or one for all) and 2-D arrays with a motion a row, giving a 2-D array
        with τ a row. ``p``: parameter values for this call only, as for :meth:`rhs`; ``u``:
        the inputs' values, as for :meth:`rhs` (a callable takes t and the state (q, q̇)).

        With constraints kept with multipliers, τ + Jᵀμ gives the same motion for every μ;
        this is the one least in τᵀ·M⁻¹·τ, which leaves the constraints the load they carry
        without it (a motion the scene makes on its own needs τ = 0). The accelerations must
        be ones the constraints allow, as those of a run of the scene are. Forces that are not
        finite raise :class:`NumericError`.
        """
        import numpy

        if self._inverse is None:
            self._inverse = self._native.inverse_dynamics()
        n = len(self._inverse.names)
        motion = [numpy.asarray(v, dtype=float) for v in (q, qd, qdd)]
        single = all(m.ndim == 1 for m in motion) and numpy.ndim(t) == 0
        rows = [numpy.atleast_2d(m) if m.size else m.reshape(0, n) for m in motion]
        count = max(len(r) for r in rows)
        rows = [numpy.broadcast_to(r, (count, r.shape[-1])) if len(r) == 1 else r for r in rows]
        times = numpy.broadcast_to(numpy.asarray(t, dtype=float), (count,))
        tau = self._inverse.batch(times, *rows, p=p, u=u)
        return tau[0] if single else tau

    def mass_matrix_function(self):
        """M(t, q) at the parameters' values: ``M(t, q)`` returns an n×n NumPy array (q may
        be the coordinates or a whole state; M does not depend on the rates)."""
        return self._native.mass_matrix_function()

    def simulate(
        self,
        until=None,
        method=None,
        tolerance=None,
        output=None,
        set=None,
        *,
        step=None,
        input=None,
        hold=None,
        stop_when=None,
        events=None,
        samples=0,
    ):
        """Integrates the scene as ``lagrange simulate`` does and returns :class:`Results`.

        Arguments left ``None`` take the scene's ``simulate`` block or the defaults.

        - ``until``: the end time in seconds; ``method``: one of rk4, bs3, dopri5, dop853,
          midpoint, gauss, radau, auto; ``tolerance`` of the adaptive methods; ``step`` of
          the fixed-step ones.
        - ``output``: scene expressions to record (a string or a list), e.g.
          ``["theta", "floor.force", "KE + PE"]``; by default every remaining coordinate.
        - ``set``: a dict of parameter, coordinate or rate (``"theta'"``) name to a number or
          a scene expression, in place of the scene's values (``{"g": 1.62}``); or texts as
          the command line takes them, ``"g=1.62"`` or a list of them.
        - ``input``: a dict of the scene's input name to what drives it, a number or a scene
          expression of ``t``, the coordinates, their rates and the parameters, such as a
          state-feedback law (``{"F": "-20*x - 5*x'"}``), or a time series as a pair
          ``(times, values)``, linear between the samples and spanning the run; or ``"F=..."``
          texts. An input not driven keeps its declared value.
        - ``hold``: a period in seconds at which the laws of ``input`` are sampled from the
          state and held until the next sample (a zero-order hold, as a discrete controller
          acts), rather than applied continuously; the scene's ``simulate { hold … }`` when
          ``None``. Time series are not held.
        - ``stop_when``: expressions (or ``"lhs = rhs"``) whose zero ends the run;
          ``events``: expressions whose zero crossings are recorded.
        - ``samples``: record at this many evenly spaced times from 0 to ``until``, both
          included, as ``numpy.linspace(0, until, samples)`` spaces them (0: at every
          accepted step instead); events, and the end of a run that stops early, come in
          addition.

        A scene with contacts runs through its impacts, lift-offs and settling as the command
        runs it; the results' ``contact_events`` are a :class:`ContactEvents` table.

        A run that faults raises :class:`NumericError` whose ``results`` hold what was
        computed before the fault.

        The GIL is released while the scene integrates, so other Python threads run
        meanwhile (several threads may simulate one scene at once), and Ctrl-C stops a long
        run with ``KeyboardInterrupt``. The scene is derived and lowered for a run's outputs,
        stops, events, inputs and method on the first call and kept: later calls that change
        only ``until``, ``tolerance``, ``step``, ``samples``, ``set`` or input series start
        integrating at once.
        """
        options = _run_options(
            until=until,
            method=method,
            tolerance=tolerance,
            output=output,
            set=set,
            step=step,
            input=input,
            hold=hold,
            stop_when=stop_when,
            events=events,
            samples=samples,
        )
        raw = self._native.simulate(options)
        results = Results(raw)
        if results.fault is not None:
            raise NumericError(results.fault, results=results)
        return results

    def batch(self, values, names=None, *, threads=1, **settings):
        """Runs the scene once per set of values and returns a :class:`Batch` of NumPy arrays,
        one entry a run.

        ``values``: a 2-D array with a run a row and a column per name of ``names``
        (parameters, coordinates for start positions, ``"theta'"`` for start rates); or a
        list of dicts of name to number (then ``names`` is left out), or a dict of name to a
        1-D array of values (one entry a run). Every run takes ``settings``, the keyword
        arguments of :meth:`simulate` (``set`` the same for all). ``threads``: how many
        threads of its own the batch runs on; the numbers are the same whatever the count.
        The GIL is released meanwhile, and Ctrl-C stops the batch.

        The scene is derived and lowered once per thread; each run settles its start and
        integrates. A run that faults has its fault in ``Batch.fault`` and its values where it
        stopped; settings that cannot run raise as :meth:`simulate` does.
        """
        names, rows = _batch_values(values, names)
        if isinstance(threads, bool) or not isinstance(threads, numbers.Integral) or threads < 1:
            raise ValueError(f"`threads` must be a positive whole number, not {threads!r}")
        options = _run_options(**settings)
        raw = self._native.batch(names, rows, int(threads), options)
        return Batch(raw, names, rows)

    def ensemble(
        self, vary, *, runs=None, seed=0, record=None, threads=None, start=0, stop=None, **settings
    ):
        """``lagrange ensemble`` on this scene: runs it over grid axes and random draws of its
        parameters, on ``threads`` threads (``None``: one per core), and returns an
        :class:`EnsembleTable` of NumPy columns, a value per run.

        - ``vary``: a dict of parameter name to ``(a, b, n)`` (a grid axis of n values from a
          to b; axes are crossed, the first varying slowest), ``"normal(mu, sigma)"`` or
          ``"uniform(a, b)"`` (``runs`` random draws from ``seed``, at each grid point); or
          texts as ``--vary`` takes them (``"a1=-3:3:60"``). A start that a parameter gives
          (``coord theta = a``) follows it.
        - ``record``: scene expressions at the end of each run (or where a stop ended it;
          ``t`` is then the stop's time), ``max(EXPR)`` and ``min(EXPR)`` over the run,
          ``impacts(NAME)`` and ``settled(NAME)`` of a contact (NaN where it did not settle); by
          default the scene's ``output`` quantities at the end, else the coordinates.
        - ``start``, ``stop``: run only these runs of the ensemble (in its order), for a front
          end that spreads chunks over processes or machines; joined in order, the chunks
          give the whole table. A ``stop`` past the last run ends there, as a slice does; a
          ``start`` at or past it, or after ``stop``, raises ``ValueError``.
        - ``settings``: :meth:`simulate`'s keyword arguments but ``output`` and ``samples``.

        The scene is derived and lowered once per call; the table is the same whatever the
        thread count, as the command's is. The GIL is released meanwhile, and Ctrl-C stops the
        ensemble. A run that fails has NaN values and its reason in ``failures``.
        """
        for unused in ("output", "samples"):
            if unused in settings:
                raise TypeError(f"an ensemble records `record`, not `{unused}`")
        options = _run_options(**settings)
        raw = self._native.ensemble(
            _vary_texts(vary),
            None if runs is None else int(runs),
            int(seed),
            _listed(record),
            None if threads is None else int(threads),
            int(start),
            None if stop is None else int(stop),
            options,
        )
        return EnsembleTable(raw)

    def linearize(
        self, about=None, set=None, sweep=None, inputs=None, outputs=None, keep_cyclic=True
    ):
        """Small motions about an equilibrium or a steady motion, as ``lagrange linearize``.

        - ``about``: ``"theta=0, phi'=2"`` (or a dict of name to value), extending or
          overriding the scene's ``linearize about`` line;
        - ``set``: a dict of parameter name to value, or ``"name=value"`` texts as for
          :meth:`simulate`;
        - ``sweep``: ``"w=0:100:201"`` or ``{"w": (0, 100, 201)}``, n values of one
          parameter from a to b;
        - ``inputs``, ``outputs``: the names of the scene's ``input`` and ``output`` lines to
          keep, in that order (the columns of B and D, the rows of C and D); all by default;
        - ``keep_cyclic``: whether the positions of cyclic coordinates stay in the state
          (the default: the state is (q, q') of every coordinate).

        Returns a :class:`Linearization`: a dict as before (``state``, the exact ``M``,
        ``C``, ``K``, ``A``, ``eigenvalues``, ``stability``, ``tolerance``, ``sweep``…) with
        the state space ẋ = A·x + B·u, y = C·x + D·u as attributes. A reference that is not an
        equilibrium raises :class:`SceneError`.
        """
        if isinstance(about, dict):
            about = ", ".join(f"{k}={_value_text(v)}" for k, v in about.items())
        raw = self._native.linearize(
            about=about, set=_assignments(set), sweep=_sweep_text(sweep), keep_cyclic=keep_cyclic
        )
        return Linearization(raw, inputs, outputs)

    def linearize_along(
        self,
        t=None,
        states=None,
        inputs=None,
        *,
        set=None,
        until=None,
        method=None,
        tolerance=None,
        step=None,
        samples=200,
    ):
        """Small motions about a motion rather than an equilibrium, as ``lagrange linearize
        --along``: A(t), B(t), C(t), D(t) at each sample and the state-transition matrix over
        the motion.

        - Without ``t``: the scene is run with its ``simulate`` settings, ``until``,
          ``method``, ``tolerance``, ``step`` and ``samples`` as for :meth:`simulate`, its
          inputs at their declared values, and linearized at every recorded sample; Φ is
          integrated beside the run on its own steps (the variational equations ``orbit``
          uses, so ``method`` must be an explicit one).
        - With ``t`` (increasing times), ``states`` (one row per time: q, then q') and, for a
          scene with inputs, ``inputs`` (one row per time; their declared values if omitted):
          the motion given, which need not be one of the scene's (a planner's reference, a
          measured motion); Φ is integrated with A(t) linear between the samples.
        - ``set``: parameter values (and, for a run, starting values) as for :meth:`simulate`.

        Returns a :class:`LinearizationAlong`. Scenes with contacts raise :class:`SceneError`;
        constraints kept with multipliers are taken as a run takes them.
        """
        import numpy as np

        options = _run_options(
            until=until, method=method, tolerance=tolerance, step=step, set=set, samples=samples
        )
        if t is None:
            if states is not None or inputs is not None:
                raise ValueError("`states` and `inputs` give a motion with its times `t`")
            raw = self._native.linearize_along(options)
        else:
            t = np.asarray(t, dtype=float)
            states = np.asarray(states, dtype=float)
            if t.ndim != 1 or states.ndim != 2 or states.shape[0] != t.shape[0]:
                raise ValueError(
                    f"`t` must be one time per sample and `states` one row per time, not shapes "
                    f"{t.shape} and {states.shape}"
                )
            if inputs is not None:
                inputs = np.asarray(inputs, dtype=float).reshape(t.shape[0], -1).tolist()
            raw = self._native.linearize_along(
                options, times=t.tolist(), states=states.tolist(), inputs=inputs
            )
        return LinearizationAlong(raw)

    def orbit(
        self,
        period=None,
        section=None,
        direction="rising",
        shift=None,
        swap=None,
        ignore=None,
        set=None,
        *,
        until=None,
        method=None,
        tolerance=None,
        iterations=30,
    ):
        """A periodic orbit, as ``lagrange orbit`` finds it: Newton's method on a return map,
        its Jacobian from the exact variational equations, and the Floquet multipliers.

        - ``period``: a fixed period for a driven scene, a number or an expression of the
          parameters (``"2*pi/w"``); or ``section``: an expression crossing zero (``"theta"``,
          ``"x = 2"``) in ``direction`` (``"rising"`` or ``"falling"``), ``"impact"`` (any
          contact's landing) or ``"impact:NAME"``.
        - ``shift``: values added to coordinates or rates before a return is compared with its
          start, a dict (``{"theta": "pi/4"}``) or ``"name=value"`` texts; ``swap``: pairs of
          coordinates exchanged with their rates (``{"a": "b"}`` or ``"a=b"``); ``ignore``:
          coordinates left out of the comparison (a cyclic one, the distance rolled).
        - ``set``, ``until``, ``method``, ``tolerance`` as for :meth:`simulate` (``until``: the
          longest a return may take); ``iterations``: the most Newton steps.

        Returns an :class:`Orbit`. No orbit found (no return, no convergence, grazing)
        raises :class:`NumericError`; bad input ``ValueError`` (an expression's mistake
        :class:`SceneError`).
        """
        if isinstance(ignore, str):
            ignore = [ignore]
        raw = self._native.orbit(
            period=None if period is None else _value_text(period),
            section=section,
            direction=direction,
            shift=_assignments(shift),
            swap=_assignments(swap),
            ignore=list(ignore or []),
            set=_assignments(set),
            until=until,
            method=method,
            tolerance=tolerance,
            iterations=iterations,
        )
        return Orbit(raw)

    def fit(
        self,
        data,
        free,
        *,
        noise=None,
        bounds=None,
        shots=1,
        set=None,
        input=None,
        method=None,
        tolerance=None,
        iterations=100,
    ):
        """Parameters and start values estimated from measurements, as ``lagrange fit``
        makes the fit: Levenberg–Marquardt on the exact sensitivities of the runs.

        - ``data``: a pandas DataFrame, or a dict of equal-length arrays, with a column ``t``
          (seconds, increasing) and columns named by scene expressions (``"theta"``,
          ``"x'"``, ``"KE"``); NaN is a value not measured.
        - ``free``: the unknowns, a list of names or one comma-separated text: parameters
          (``"c"``) and start values (``"theta(0)"``, ``"theta'(0)"``); or a dict of name to
          the value to start from (in SI). Without a value, the scene's.
        - ``noise``: a dict of column to its noise level; each residual is divided by its
          column's (1 where none is given). ``bounds``: a dict of unknown to ``(low, high)``
          (``None`` for an open side).
        - ``shots``: multiple shooting over this many shots, for long or chaotic records.
        - ``set``, ``input`` (measured inputs as ``(t, values)`` series, or laws), ``method``,
          ``tolerance`` as for :meth:`simulate`; ``iterations``: the most
          Levenberg–Marquardt iterations.

        Returns a :class:`Fit`. Bad data or names raise ``ValueError`` with the place marked;
        a run that faults :class:`NumericError`.
        """
        options = _run_options(method=method, tolerance=tolerance, set=set, input=input)
        if isinstance(free, str):
            free_text = free
        elif isinstance(free, dict):
            free_text = ", ".join(
                name if start is None else f"{name}={float(start)!r}" for name, start in free.items()
            )
        else:
            free_text = ", ".join(free)
        bound_texts = []
        for name, (low, high) in (bounds or {}).items():
            low = "" if low is None else repr(float(low))
            high = "" if high is None else repr(float(high))
            bound_texts.append(f"{name}={low}:{high}")
        raw = self._native.fit(
            _data_text(data),
            free_text,
            options,
            noise=[(name, float(sigma)) for name, sigma in (noise or {}).items()],
            bounds=bound_texts,
            shots=int(shots),
            iterations=int(iterations),
        )
        return Fit(raw)

    def check(self):
        """Checks every ``expect`` line of the scene: a list of :class:`Expectation`."""
        return [Expectation(**item) for item in self._native.check()]

    def __repr__(self):
        title = f" {self.title!r}" if self.title else ""
        return f"<lagrange.Scene{title} from {self.path}>"


def _chosen(names, chosen, what):
    """The indices of ``chosen`` among ``names`` (all of them for ``None``)."""
    if chosen is None:
        return list(range(len(names)))
    if isinstance(chosen, str):
        chosen = [chosen]
    unknown = [c for c in chosen if c not in names]
    if unknown:
        known = ", ".join(names) or "none"
        raise ValueError(f"no {what} {unknown[0]!r} in the scene (its {what}s: {known})")
    return [names.index(c) for c in chosen]


class Orbit(dict):
    """A periodic orbit: the dict ``Scene.orbit`` gives, with its parts as attributes.

    - ``state``: the names of (q, q'); ``fixed_point``: the map's fixed point on the section,
      a NumPy array; ``period``: the time the map takes there.
    - ``multipliers``: the Floquet multipliers on the section, complex, largest modulus first;
      ``trivial``: how many directions (the flow's, the kept constraints' normals, the
      ignored coordinates) were left out.
    - ``monodromy``: the map's Jacobian on the whole state, a NumPy array.
    - ``stable``: every multiplier inside the unit circle; ``verdict``: ``"stable"``,
      ``"neutral"`` (one on the unit circle, within 1e-6: a family of orbits, or the edge of
      stability) or ``"unstable"``; ``jumps``: the contacts' jumps on the way; ``residuals``:
      Newton's, on the section, before each step; ``tolerances``: each run's (loose far from
      the orbit, the one asked for near it); ``last_step``: where the last step was taken
      without a run to check it, the residual it is expected to leave, else None.
    """

    def __init__(self, raw):
        import numpy as np

        raw = dict(raw)
        raw["multipliers"] = [complex(re, im) for re, im in raw["multipliers"]]
        raw["monodromy"] = np.array(raw["monodromy"], dtype=float)
        super().__init__(raw)
        for key, value in raw.items():
            setattr(self, key, value)

    def __repr__(self):
        verdict = self["verdict"]
        largest = max((abs(m) for m in self["multipliers"]), default=0.0)
        return f"<lagrange.Orbit period {self['period']:.6g} s, {verdict}, max |μ| {largest:.6g}>"


def _data_text(data):
    """Measurements as the CSV text a fit reads: the columns of a DataFrame or a dict of
    arrays, every number in full (``repr`` gives a float's shortest exact digits), NaN as an
    empty cell."""
    import math

    import numpy as np

    names = [str(name) for name in data.keys()] if hasattr(data, "keys") else None
    if names is None:
        raise TypeError(f"`data` must be a DataFrame or a dict of arrays, not {type(data).__name__}")
    columns = [np.asarray(data[name], dtype=float).ravel() for name in data.keys()]
    lengths = {len(c) for c in columns}
    if len(lengths) > 1:
        raise ValueError(f"the columns of `data` differ in length: {sorted(lengths)}")
    lines = [",".join(names)]
    for row in zip(*columns):
        lines.append(",".join("" if math.isnan(v) else repr(float(v)) for v in row))
    return "\n".join(lines) + "\n"


class Fit(dict):
    """A fit: the dict ``Scene.fit`` gives, with its parts as attributes.

    - ``names``: the unknowns; ``kinds``: ``"parameter"`` or ``"start"`` each;
      ``estimates``, ``standard_errors``, ``initial``: NumPy arrays in that order (a
      standard error is infinite for an unknown the data cannot fix); ``covariance`` and
      ``correlation``: NumPy arrays; ``values``: a dict of name to estimate.
    - ``rms``: per column, its residuals' RMS and how many values; ``t`` and ``model``: the
      data's times and the fitted model's value of each column there.
    - ``cost``: Σ r² at the optimum, ``variance``: Σ r²/(N − k), by which the covariance is
      scaled; ``iterations``, ``evaluations``, ``shots``, ``converged``, ``ending``.
    - ``unidentifiable``: ``None``, or the combination (name, coefficient of δθ/θ) along
      which the residuals do not change.
    - ``scene``: the scene's text with the fitted values written in.
    """

    def __init__(self, raw):
        import numpy as np

        raw = dict(raw)
        raw["covariance"] = np.array(raw["covariance"], dtype=float)
        raw["correlation"] = np.array(raw["correlation"], dtype=float)
        raw["values"] = dict(zip(raw["names"], (float(v) for v in raw["estimates"])))
        super().__init__(raw)
        for key, value in raw.items():
            setattr(self, key, value)

    def __repr__(self):
        parts = ", ".join(
            f"{n} = {v:.6g} ± {e:.2g}"
            for n, v, e in zip(self["names"], self["estimates"], self["standard_errors"])
        )
        return f"<lagrange.Fit {parts}{'' if self['converged'] else ' (not converged)'}>"


class Linearization(dict):
    """Small motions about a reference: the dict ``Scene.linearize`` always gave, with the
    state space ẋ = A·x + B·u, y = C·x + D·u as attributes.

    - ``state``: the names of x; ``inputs`` and ``outputs``: those of u and y, as chosen.
    - ``A``, ``B``, ``C``, ``D``: NumPy arrays at the parameters' values. Without outputs,
      C is the identity (y = x) and D is zero, so that a controller sees the whole state.
    - ``A_sym``, ``B_sym``, ``C_sym``, ``D_sym``: the same as SymPy matrices, exact
      (expressions of the parameters) where the algebra gives them (no constraint kept), else
      the numbers as ``sympy.Float``; ``exact`` says which.
    - ``controllability``, ``observability``: ``{rank, of, tolerance, smallest_counted,
      largest_left_out, doubtful}`` (``None`` without inputs, outputs).
    - ``to_control()``: a ``control.StateSpace``, with python-control installed.
    """

    def __init__(self, raw, inputs=None, outputs=None):
        super().__init__(raw)
        import numpy as np
        import sympy as sp

        columns = _chosen(raw["inputs"], inputs, "input")
        rows = _chosen(raw["outputs"], outputs, "output")
        self.inputs = [raw["inputs"][k] for k in columns]
        self.outputs = [raw["outputs"][k] for k in rows]
        self.A = raw["A"]
        n = self.A.shape[0]
        self.B = raw["B"][:, columns]
        if raw["outputs"]:
            self.C = raw["C"][rows, :]
            self.D = raw["D"][rows, :][:, columns]
        else:
            self.C, self.D = np.eye(n), np.zeros((n, len(columns)))
        exact = raw.get("exact")
        self.exact = exact is not None
        if exact is not None:
            self.A_sym = exact["A"]
            self.B_sym = exact["B"].extract(list(range(n)), columns)
            if raw["outputs"]:
                self.C_sym = exact["C"].extract(rows, list(range(n)))
                self.D_sym = exact["D"].extract(rows, columns)
            else:
                self.C_sym, self.D_sym = sp.eye(n), sp.zeros(n, len(columns))
        else:
            self.A_sym, self.B_sym, self.C_sym, self.D_sym = (
                sp.Matrix(m.shape[0], m.shape[1], [sp.Float(x) for x in m.flat])
                for m in (self.A, self.B, self.C, self.D)
            )
        self.controllability = raw.get("controllability")
        self.observability = raw.get("observability")

    @property
    def state(self):
        return self["state"]

    def to_control(self):
        """The state space as ``control.StateSpace`` (python-control must be installed)."""
        try:
            import control
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("to_control() needs python-control: pip install control") from e
        return control.ss(self.A, self.B, self.C, self.D)

    def __repr__(self):
        return (
            f"<lagrange.Linearization {self['stability']}: {len(self.state)} states, "
            f"{len(self.inputs)} inputs, {len(self.outputs)} outputs>"
        )


class LinearizationAlong:
    """The small motions about a motion, ẋ = A(t)·x + B(t)·u, y = C(t)·x + D(t)·u, at its
    samples (see :meth:`Scene.linearize_along`).

    - ``t``: the samples' times; ``state``, ``inputs``, ``outputs``: the names of x, u, y.
    - ``A``, ``B``, ``C``, ``D``: NumPy arrays stacked over the samples, ``A[k]`` at ``t[k]``
      (shapes samples × n × n, samples × n × inputs, samples × outputs × n, samples ×
      outputs × inputs).
    - ``transition``: Φ(t[-1], t[0]), δx(t[-1]) = Φ·δx(t[0]) with the inputs held on the
      motion; ``transition_method``: ``"model"`` (the variational equations beside the run) or
      ``"interpolated"`` (A linear between them).
    - ``to_control(k)``: the state space at sample ``k`` as ``control.StateSpace``.
    """

    def __init__(self, raw):
        self.state = raw["state"]
        self.inputs = raw["inputs"]
        self.outputs = raw["outputs"]
        self.t = raw["t"]
        self.A, self.B, self.C, self.D = raw["A"], raw["B"], raw["C"], raw["D"]
        self.transition = raw["transition"]["matrix"]
        self.transition_method = raw["transition"]["method"]

    def __len__(self):
        return len(self.t)

    def to_control(self, k):
        """The state space at sample ``k`` as ``control.StateSpace`` (python-control must be
        installed). Without outputs, C is the identity (y = x), as for :class:`Linearization`."""
        try:
            import control
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("to_control() needs python-control: pip install control") from e
        import numpy as np

        a, b = self.A[k], self.B[k]
        if self.outputs:
            c, d = self.C[k], self.D[k]
        else:
            c, d = np.eye(a.shape[0]), np.zeros((a.shape[0], b.shape[1]))
        return control.ss(a, b, c, d)

    def __repr__(self):
        return (
            f"<lagrange.LinearizationAlong of {len(self)} samples from t = {self.t[0]} to "
            f"{self.t[-1]}, x = ({', '.join(self.state)})>"
        )


class Derivation:
    """Everything ``lagrange derive`` shows, as SymPy objects.

    Coordinates are functions of time ``t`` (``theta(t)``); their rates and accelerations
    are ``Derivative``s of them; parameters and reactions are ``Symbol``s named as in the
    scene (``g``, ``floor.force``); numbers are exact.

    Attributes:

    - ``t``: the time symbol; ``coordinates``, ``rates``, ``accelerations``: the remaining
      coordinates (those constraints did not eliminate) and their derivatives;
      ``multipliers``: the reactions of constraints kept with multipliers.
    - ``parameters``: dict of parameter name to its value as a float (``None`` if it has
      none); ``derived_parameters``: dict of each derived parameter's name (one whose value
      names others, ``param L = 2*a``) to the names of the parameters it follows, which are
      the ones to set; ``symbols``: dict of every scene name (``"theta''"`` included) to its SymPy object.
    - ``mass_matrix`` (n×n) and ``forcing`` (n×1): ``sympy.Matrix`` with M·q̈ = f.
    - ``equations``: the equations of motion as ``sympy.Eq``, as the report writes them.
    - ``kinetic``, ``potential``, ``lagrangian``: T, V and L.
    - ``reactions``: dict of reaction name (``"floor.force"``) to its expression (with
      accelerations); ``reactions_of_state``: with the accelerations solved for.
    - ``shown``: the scene's ``show`` items; ``at_start``: its ``show at start`` items at the
      initial state, keyed as written in the scene (``"theta''"``), exact where the algebra
      allows (``at_start_note`` says when they are numbers instead); ``start``: the initial
      state.
    - ``constraints``: a list of :class:`Constraint`.
    - ``independent``: where velocity constraints are kept and no reaction is asked for, the
      equations in the independent rates (Maggi's form) as a dict: ``dependent`` (each
      dependent rate's name to its expression), ``independent`` (the independent rates) and
      ``equations`` (``sympy.Eq(…, 0)``); ``None`` otherwise.
    - ``latex``: the equations, mass-matrix form, reactions and start values in LaTeX.
    """

    def __init__(self, raw, scene=None):
        self._scene = scene
        self.title = raw["title"]
        self.t = raw["t"]
        self.coordinates = raw["coordinates"]
        self.rates = raw["rates"]
        self.accelerations = raw["accelerations"]
        self.multipliers = raw["multipliers"]
        self.parameters = raw["parameters"]
        self.derived_parameters = raw["derived_parameters"]
        self.symbols = raw["symbols"]
        self.mass_matrix = raw["mass_matrix"]
        self.forcing = raw["forcing"]
        self.equations = raw["equations"]
        self.kinetic = raw["kinetic"]
        self.potential = raw["potential"]
        self.lagrangian = raw["lagrangian"]
        self.reactions = raw["reactions"]
        self.reactions_of_state = raw["reactions_of_state"]
        self.shown = raw["shown"]
        self.at_start = raw["at_start"]
        self.at_start_note = raw["at_start_note"]
        self.start = raw["start"]
        self.constraints = [Constraint(**c) for c in raw["constraints"]]
        self.independent = raw["independent"]
        self.latex = raw["latex"]

    def parameter_values(self):
        """``{symbol: value}`` of the parameters that have values, for ``expr.subs(...)``."""
        return {
            self.symbols[name]: value
            for name, value in self.parameters.items()
            if value is not None
        }

    def inverse_dynamics(self, t, q, qd, qdd, p=None, u=None):
        """The generalized forces of a motion: :meth:`Scene.inverse_dynamics` of the scene
        this derivation is of."""
        return self._scene.inverse_dynamics(t, q, qd, qdd, p=p, u=u)

    def _repr_latex_(self):
        return self.latex

    def __repr__(self):
        coords = ", ".join(str(q) for q in self.coordinates)
        return f"<lagrange.Derivation of ({coords}): {len(self.equations)} equations>"


@dataclass
class Constraint:
    """A constraint of the scene: ``equation`` as written (``sympy.Eq``), ``phi`` = lhs − rhs,
    ``kind`` (``"position"``, ``"velocity"`` or ``"contact"``, a one-sided
    contact whose gap is ``phi``, which a run opens and closes), ``reaction`` (its ``NAME.force`` symbol) and
    ``handling``: ``"eliminated"`` (then ``solved_for`` is the coordinate it removed and
    ``solution`` its value), ``"kept"`` with a multiplier, or ``"dropped"`` (always holds)."""

    name: str
    kind: str
    equation: object
    phi: object
    reaction: object
    handling: str
    solved_for: object = None
    solution: object = None


@dataclass
class Expectation:
    """One ``expect`` line and its verdict: ``line`` in the file, ``text`` as written,
    ``held``, and ``how`` it was decided ("holds exactly", "DOES NOT HOLD", …). One that fails
    has its ``residual`` (lhs − rhs, SymPy) and a ``state`` where it is not zero."""

    line: int
    text: str
    held: bool
    how: str
    residual: object = None
    state: dict = field(default=None)
    component: int = None

    def __bool__(self):
        return self.held


class _Columns(Mapping):
    """A mapping of names to NumPy arrays, kept in ``_columns``: what :class:`Results` and
    :class:`Batch` are besides their attributes."""

    def __getitem__(self, name):
        return self._columns[name]

    def __iter__(self):
        return iter(self._columns)

    def __len__(self):
        return len(self._columns)

    def _pandas(self, what):
        """pandas, or an ImportError that says ``what`` needs it."""
        try:
            import pandas
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError(f"{what} needs pandas: pip install pandas") from e
        return pandas


class Results(_Columns):
    """A simulation: a mapping of each recorded quantity's name (and ``"t"``) to a NumPy
    array, one value per recorded time.

    Besides: ``energy`` (T + V at each time), ``events`` (a list of ``(name, time)``),
    ``stopped_by`` (the stop condition that ended the run, or ``None``), ``method``,
    ``segments`` (which method ran over which span of time: a list of
    ``(method, start, end)``, several when ``auto`` switched), ``steps``, ``rejected``, ``evaluations``, ``jacobians`` and ``factorizations`` (radau's),
    ``energy_drift`` (largest absolute and relative change of T + V), ``conservative`` (whether the scene should keep its energy),
    ``constraint_drift`` (over the recorded times; ``constraint_drift_at_steps`` at the
    integrator's own steps), ``wall_seconds`` and ``fault`` (``None`` for a finished run).

    With contacts: ``contacts`` (their names, as written), ``contact_events`` (a
    :class:`ContactEvents` table of the impacts, lift-offs and settlings) and
    ``energy_changed_by_impacts`` (what the impacts changed T + V by in all; ``energy_drift``
    is measured less it). A run's rows hold the state before and after each impact at the
    same time.
    """

    def __init__(self, raw):
        self.t = raw["t"]
        self._columns = {"t": raw["t"], **raw["columns"]}
        self.energy = raw["energy"]
        self.events = raw["events"]
        self.stopped_by = raw["stopped_by"]
        self.fault = raw["fault"]
        self.method = raw["method"]
        self.segments = raw["segments"]
        self.steps = raw["steps"]
        self.rejected = raw["rejected"]
        self.evaluations = raw["evaluations"]
        self.jacobians = raw["jacobians"]
        self.factorizations = raw["factorizations"]
        self.energy_drift = raw["energy_drift"]
        self.conservative = raw["conservative"]
        self.constraint_drift = raw["constraint_drift"]
        self.constraint_drift_at_steps = raw["constraint_drift_at_steps"]
        self.wall_seconds = raw["wall_seconds"]
        self.contacts = raw["contacts"]
        self.contact_events = ContactEvents(raw["contact_events"])
        self.energy_changed_by_impacts = raw["energy_changed_by_impacts"]

    def to_pandas(self):
        """The columns as a ``pandas.DataFrame`` indexed by ``t`` (needs pandas)."""
        pandas = self._pandas("Results.to_pandas")
        columns = {k: v for k, v in self._columns.items() if k != "t"}
        return pandas.DataFrame(columns, index=pandas.Index(self.t, name="t"))

    def __repr__(self):
        names = ", ".join(k for k in self._columns if k != "t")
        return f"<lagrange.Results {len(self.t)} times of ({names}), {self.method}>"


class ContactEvents(_Columns):
    """The contact events of a run, in the order they happened: a mapping of each column's
    name to a NumPy array with an entry an event, as ``lagrange simulate --events`` writes
    them.

    - ``t``: when;
    - ``contact``: the contact's name (strings);
    - ``kind``: ``"impact"`` (it landed and took an impulse by Newton's law),
      ``"settled"`` (its impacts accumulate: the last one made plastic, the contact closed),
      ``"closed"`` (it closed touching at rest), ``"lift-off"`` (its reaction fell to zero),
      ``"struck"`` (another contact's impact gave it an impulse while it stayed closed),
      ``"sticks"`` and ``"slips"`` (a rough contact's friction began to hold it, or it began
      to slip);
    - ``closed``: whether the contact is closed after it (bools);
    - ``impulse``: the normal impulse it took (0 without an impact);
    - ``tangential_impulse``: its grip's impulse (NaN for a contact without grip);
    - ``energy_change``: the kinetic energy its impulses changed;
    - ``slip``: a rough contact's slip after it, ±1 the way it slips, 0 sticking (0 for a
      contact without friction).

    ``len(events)`` is the number of columns, as for any mapping; ``events.count`` the number
    of events. ``events.of(kind)`` is the times of one kind, ``events.settled(name)`` the
    time a contact settled (``None`` if it did not).
    """

    def __init__(self, raw):
        self._columns = {
            "t": raw["t"],
            "contact": numpy.array(raw["contact"], dtype=str).reshape(-1),
            "kind": numpy.array(raw["kind"], dtype=str).reshape(-1),
            "closed": raw["closed"],
            "impulse": raw["impulse"],
            "tangential_impulse": raw["tangential_impulse"],
            "energy_change": raw["energy_change"],
            "slip": raw["slip"],
        }

    @property
    def count(self):
        """The number of events."""
        return len(self._columns["t"])

    def of(self, kind, contact=None):
        """The times of the events of ``kind`` (of ``contact`` alone, if named)."""
        picked = self._columns["kind"] == kind
        if contact is not None:
            picked &= self._columns["contact"] == contact
        return self._columns["t"][picked]

    def settled(self, contact=None):
        """When ``contact`` (any, if ``None``) settled, or ``None`` if it did not."""
        times = self.of("settled", contact)
        return float(times[0]) if len(times) else None

    def to_pandas(self):
        """A ``pandas.DataFrame`` with a row an event (needs pandas)."""
        pandas = self._pandas("ContactEvents.to_pandas")
        return pandas.DataFrame(self._columns)

    def __repr__(self):
        kinds = ", ".join(
            f"{int((self._columns['kind'] == k).sum())} {k}"
            for k in dict.fromkeys(self._columns["kind"].tolist())
        )
        return f"<lagrange.ContactEvents {self.count} events{': ' + kinds if kinds else ''}>"


class Batch(_Columns):
    """The runs of :meth:`Scene.batch`: a mapping of each recorded quantity's name (and
    ``"t"``) to a NumPy array with an entry per run, its value where the run ended (at
    ``until``, or where a stop condition ended it).

    Besides: ``names`` and ``values`` (the batch's values, a row a run), ``stopped_by`` and
    ``fault`` (lists, ``None`` where none), ``steps`` and ``wall_seconds`` (arrays); with
    ``samples``, ``samples_t`` (the times) and ``samples[name]``, a 2-D array with a row a run
    (NaN after a run's stop).
    """

    def __init__(self, raw, names, values):
        self.names = list(names)
        self.values = values
        self.t = raw["t"]
        self._columns = {"t": raw["t"], **raw["columns"]}
        self.stopped_by = raw["stopped_by"]
        self.fault = raw["fault"]
        self.steps = raw["steps"]
        self.wall_seconds = raw["wall_seconds"]
        sampled = raw.get("samples")
        self.samples_t = None if sampled is None else sampled.pop("t")
        self.samples = sampled

    def to_pandas(self):
        """One row a run: the values varied, then where each run ended (needs pandas)."""
        pandas = self._pandas("Batch.to_pandas")
        frame = pandas.DataFrame(self.values, columns=self.names)
        for name, column in self._columns.items():
            frame[name if name not in self.names else f"{name} (end)"] = column
        return frame

    def __repr__(self):
        names = ", ".join(k for k in self._columns if k != "t")
        return f"<lagrange.Batch {len(self.t)} runs of ({names})>"


class EnsembleTable(_Columns):
    """The table of :meth:`Scene.ensemble`: a mapping of each column's name (the varied
    parameters, then the recorded quantities as written) to a NumPy array with a value per
    run, in the ensemble's order.

    Besides: ``varied`` (the varied parameters' names), ``recorded`` (the recorded columns'
    names), ``failures`` (a reason, or ``None``, per run), ``axes`` (each grid axis's name to
    its values), ``random`` (whether some values were drawn) and ``runs`` (how many runs the
    whole ensemble has, of which a ``start``/``stop`` chunk holds some).
    """

    def __init__(self, raw):
        self._columns = dict(raw["columns"])
        names = list(self._columns)
        self.varied = names[: raw["varied"]]
        self.recorded = names[raw["varied"] :]
        self.failures = raw["failures"]
        self.axes = {name: values for name, values in raw["axes"]}
        self.random = raw["random"]
        self.runs = raw["runs"]

    def to_pandas(self):
        """A ``pandas.DataFrame`` with a row a run, as ``--out FILE.csv`` writes it (needs
        pandas)."""
        pandas = self._pandas("EnsembleTable.to_pandas")
        frame = pandas.DataFrame(self._columns)
        frame["fault"] = self.failures
        return frame

    def __repr__(self):
        return (
            f"<lagrange.EnsembleTable {len(self.failures)} runs of ({', '.join(self.varied)}): "
            f"{', '.join(self.recorded)}>"
        )
