"""The lagrange package from Python: the problem-set results exactly through SymPy, the rhs
against SciPy and against lagrange's own integrator, errors, and what a notebook shows."""

import ast
import importlib.metadata
import re
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import lagrange

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"


@pytest.fixture(scope="module")
def rod():
    return lagrange.load(EXAMPLES / "ps5" / "falling_rod.lag")


def test_falling_rod_start_is_exact(rod):
    d = rod.derive()
    g, L, m = sp.symbols("g L m")
    # Exactly, not to a tolerance: the same SymPy expressions.
    assert d.at_start["theta''"] == 12 * g / (7 * L)
    assert d.at_start["floor.force"] == sp.Rational(4, 7) * m * g
    assert d.symbols["g"] == g
    assert d.parameters == {"m": 1.0, "L": 1.0, "g": 9.81}


def test_falling_rod_equations_and_reaction(rod):
    d = rod.derive()
    t = d.t
    x, theta = d.coordinates
    assert [str(q) for q in d.coordinates] == ["x(t)", "theta(t)"]
    assert d.rates[1] == sp.Derivative(theta, t)
    m, L, g = (d.symbols[k] for k in ("m", "L", "g"))
    M = d.mass_matrix
    assert M.shape == (2, 2)
    assert sp.simplify(M[1, 1] - m * L**2 * (1 + 3 * sp.sin(theta) ** 2) / 12) == 0
    assert M[0, 1] == 0 and M[0, 0] == m
    # The hand-derived equation of motion is the derived one.
    th, thd, thdd = theta, d.rates[1], d.accelerations[1]
    hand = thdd * (1 + 3 * sp.sin(th) ** 2) + 3 * thd**2 * sp.sin(th) * sp.cos(th) - 6 * g / L * sp.sin(th)
    eq = d.equations[1]
    assert sp.simplify((eq.lhs - eq.rhs) - hand) == 0
    # M q̈ = f holds for the equations: substitute the accelerations solved from M, f.
    qdd = M.LUsolve(d.forcing)
    assert sp.simplify(qdd[1] - sp.solve(hand, thdd)[0]) == 0
    floor = d.constraints[0]
    assert floor.name == "floor" and floor.handling == "eliminated"
    assert str(floor.solved_for) == "y(t)"
    assert "floor.force" in d.reactions


def test_wedge_mass_matrix():
    d = lagrange.load(EXAMPLES / "ps5" / "wedge.lag").derive()
    M_, m, theta = (d.symbols[k] for k in ("M", "m", "theta"))
    expected = sp.Matrix([[M_ + m, m * sp.cos(theta)], [m * sp.cos(theta), m]])
    assert sp.simplify(d.mass_matrix - expected) == sp.zeros(2, 2)
    g = d.symbols["g"]
    assert sp.simplify(d.forcing - sp.Matrix([0, m * g * sp.sin(theta)])) == sp.zeros(2, 1)


def test_rolling_disk_kinetic_energy():
    d = lagrange.load(EXAMPLES / "ps5" / "rolling_disk.lag").derive()
    m, r, R = (d.symbols[k] for k in ("m", "r", "R"))
    thetadot = d.symbols["theta'"]
    expected = sp.Rational(3, 4) * m * (R + r) ** 2 * thetadot**2
    assert sp.simplify(d.kinetic - expected) == 0
    assert sp.simplify(d.shown["KE"] - expected) == 0
    assert sp.simplify(d.shown["disk.omega"] - (R + r) / r * thetadot) == 0


def test_check_reports_every_expectation():
    results = lagrange.load(EXAMPLES / "ps5" / "falling_rod.lag").check()
    assert len(results) == 4
    assert all(r.held for r in results)
    assert results[2].line == 20 and results[2].how == "holds exactly"
    assert "12/7*g/L" in results[2].text


def test_a_wrong_expectation_fails_with_its_residual():
    scene = lagrange.loads(
        "param m = 1 kg, L = 1 m, g = 9.81 m/s^2\n"
        "coord theta = 1/2\n"
        "particle bob { mass m; position (L*sin(theta), -L*cos(theta)) }\n"
        "gravity g\n"
        "expect theta'' = g/L*sin(theta)\n"
    )
    (result,) = scene.check()
    assert not result.held and result.how == "DOES NOT HOLD"
    assert result.line == 5
    assert result.residual is not None and result.state


def test_rhs_with_solve_ivp_agrees_with_simulate():
    from scipy.integrate import solve_ivp

    scene = lagrange.load(EXAMPLES / "classics" / "simple_pendulum.lag")
    f = scene.rhs()
    assert f.names == ["theta", "theta'"]
    np.testing.assert_allclose(f.y0, [0.5, 0.0])
    # θ̈ = −g/L·sin θ at the start.
    np.testing.assert_allclose(f(0.0, f.y0), [0.0, -9.81 * np.sin(0.5)], rtol=1e-15)
    run = scene.simulate(until=2.0, output=["theta", "theta'"], tolerance=1e-12)
    sol = solve_ivp(f, (0.0, 2.0), f.y0, method="DOP853", rtol=1e-13, atol=1e-13, t_eval=run["t"])
    assert sol.success
    np.testing.assert_allclose(sol.y[0], run["theta"], atol=1e-8)
    np.testing.assert_allclose(sol.y[1], run["theta'"], atol=1e-8)


def test_batch_evaluates_rows_like_single_calls():
    f = lagrange.load(EXAMPLES / "classics" / "double_pendulum.lag").rhs()
    rng = np.random.default_rng(1)
    Y = rng.normal(size=(50, len(f.names)))
    times = np.linspace(0.0, 1.0, 50)
    out = f.batch(Y, t=times)
    assert out.shape == Y.shape
    for k in range(len(Y)):
        np.testing.assert_array_equal(out[k], f(times[k], Y[k]))
    # Rows are states however the array is laid out in memory.
    np.testing.assert_array_equal(f.batch(np.asfortranarray(Y), t=times), out)
    # With kept multipliers too (the augmented system solved per row).
    g = lagrange.load(EXAMPLES / "classics" / "pendulum_cartesian.lag").rhs()
    Z = np.tile(g.y0, (11, 1)) + 1e-3 * rng.normal(size=(11, len(g.names)))
    for row, single in zip(g.batch(Z), Z):
        np.testing.assert_array_equal(row, g(0.0, single))
    with pytest.raises(ValueError):
        f.batch(np.zeros((3, len(f.names) + 1)))
    with pytest.raises(ValueError):
        f(0.0, [1.0])


def central_differences(f, t, y, h=1e-5):
    """∂f/∂y by central differences, column after column."""
    columns = []
    for k in range(len(y)):
        step = h * max(1.0, abs(y[k]))
        plus, minus = np.array(y, dtype=float), np.array(y, dtype=float)
        plus[k] += step
        minus[k] -= step
        columns.append((f(t, plus) - f(t, minus)) / (2 * step))
    return np.stack(columns, axis=1)


@pytest.mark.parametrize(
    "example", ["classics/double_pendulum.lag", "classics/pendulum_cartesian.lag"]
)
def test_jac_is_the_jacobian_of_the_rhs(example):
    f = lagrange.load(EXAMPLES / example).rhs()
    n = len(f.names)
    rng = np.random.default_rng(7)
    for y in [f.y0, f.y0 + 0.1 * rng.normal(size=n)]:
        J = f.jac(0.3, y)
        assert J.shape == (n, n)
        differenced = central_differences(f, 0.3, y)
        # Each row against its own size, so that a dropped partial shows however small its
        # row; a row that vanishes but for rounding against the matrix.
        scale = np.maximum(np.abs(J).max(axis=1, keepdims=True), 1e-6 * np.abs(J).max())
        assert (np.abs(J - differenced) / scale).max() < 1e-6
    with pytest.raises(ValueError):
        f.jac(0.0, [1.0])


@pytest.mark.parametrize(
    "example",
    ["classics/double_pendulum.lag", "classics/car_axis.lag", "space/heavy_top.lag"],
)
def test_rhs_from_the_loaded_derivation_is_the_rhs_derived_afresh(example):
    """`rhs()` lays its numbers out from a copy of the loaded scene's derivation; after
    `derive()` has added its forms, and when unpickled, it derives the text again. All three
    give the same bits, and so does M."""
    import pickle

    text = (EXAMPLES / example).read_text()
    copied = lagrange.loads(text)
    f, M = copied.rhs(), copied.mass_matrix_function()
    touched = lagrange.loads(text)
    touched.derive()
    afresh, M_afresh = touched.rhs(), touched.mass_matrix_function()
    unpickled = pickle.loads(pickle.dumps(f))
    n = len(f.names)
    rng = np.random.default_rng(3)
    for y in [f.y0, f.y0 + 0.2 * rng.normal(size=n)]:
        value = f(0.4, y)
        assert value.tobytes() == afresh(0.4, y).tobytes()
        assert value.tobytes() == unpickled(0.4, y).tobytes()
        assert f.jac(0.4, y).tobytes() == afresh.jac(0.4, y).tobytes()
        q = y[: len(M.names)]
        assert M(0.4, q).tobytes() == M_afresh(0.4, q).tobytes()


def test_radau_with_the_exact_jacobian_agrees_with_dop853():
    from scipy.integrate import solve_ivp

    f = lagrange.load(EXAMPLES / "classics" / "double_pendulum.lag").rhs()
    reference = solve_ivp(f, (0.0, 2.0), f.y0, method="DOP853", rtol=1e-12, atol=1e-12)
    radau = solve_ivp(f, (0.0, 2.0), f.y0, method="Radau", jac=f.jac, rtol=1e-9, atol=1e-9)
    assert reference.success and radau.success
    # With the Jacobian given, SciPy never differences f for it.
    assert radau.njev > 0
    np.testing.assert_allclose(radau.y[:, -1], reference.y[:, -1], atol=1e-6)


def test_mass_matrix_function_matches_sympy():
    scene = lagrange.load(EXAMPLES / "ps5" / "falling_rod.lag")
    M = scene.mass_matrix_function()
    d = scene.derive()
    q = [0.3, 0.7]
    values = d.parameter_values()
    values.update(dict(zip(d.coordinates, q)))
    exact = np.array(d.mass_matrix.subs(values).evalf(), dtype=float)
    np.testing.assert_allclose(M(0.0, q), exact, rtol=1e-14)


def test_simulate_returns_named_arrays():
    scene = lagrange.load(EXAMPLES / "ps5" / "falling_rod.lag")
    run = scene.simulate(until=1.0, output=["theta", "floor.force"], set={"g": 9.8})
    assert set(run) == {"t", "theta", "floor.force"}
    assert run["t"].shape == run["theta"].shape
    assert run.stopped_by is not None  # the rod lies flat before t = 1
    np.testing.assert_allclose(run["theta"][-1], np.pi / 2, atol=1e-9)
    # At the start N = 4/7·m·g, with g as set.
    np.testing.assert_allclose(run["floor.force"][0], 4 / 7 * 9.8, rtol=1e-12)
    pandas = pytest.importorskip("pandas")
    frame = run.to_pandas()
    assert isinstance(frame, pandas.DataFrame) and list(frame.columns) == ["theta", "floor.force"]


def test_set_takes_a_dict_or_the_command_line_s_texts():
    scene = lagrange.load(EXAMPLES / "ps5" / "falling_rod.lag")
    runs = [
        scene.simulate(until=0.1, output="floor.force", set=given)
        for given in ({"g": 1.62}, "g=1.62", ["g=1.62"], ["g = 81/50"])
    ]
    for run in runs:
        np.testing.assert_allclose(run["floor.force"][0], 4 / 7 * 1.62, rtol=1e-12)
    with pytest.raises(ValueError) as caught:
        scene.simulate(until=0.1, set="g")
    assert str(caught.value) == "`set` `g`: not of the form name=value (like g=1.62)", caught.value


def test_sweep_takes_a_text_or_a_dict():
    top = lagrange.load(EXAMPLES / "space" / "sleeping_top.lag")
    as_text = top.linearize(sweep="w=0:100:11")["sweep"]["changes"]
    as_dict = top.linearize(sweep={"w": (0, 100, 11)})["sweep"]["changes"]
    assert as_text == as_dict and len(as_text) > 0


def test_bad_scene_raises_scene_error_with_position():
    text = "param m = 1 kg\ncoord x = 0\nparticle p { mass m; position (x, y) }\n"
    with pytest.raises(lagrange.SceneError) as caught:
        lagrange.loads(text, name="bad.lag")
    e = caught.value
    assert isinstance(e, Exception)
    assert (e.file, e.line, e.column) == ("bad.lag", 3, 35)
    assert "unknown name `y`" in str(e)
    # Rendered as the command prints it: file:line:column, the line, a caret.
    assert "bad.lag:3:35" in e.rendered
    assert "particle p { mass m; position (x, y) }" in e.rendered
    assert "^" in e.rendered
    assert e.diagnostics[0][0] == "error"


def test_parse_error_and_bad_options():
    with pytest.raises(lagrange.SceneError) as caught:
        lagrange.loads("coord x = \n")
    assert caught.value.line == 1
    scene = lagrange.load(EXAMPLES / "classics" / "simple_pendulum.lag")
    with pytest.raises(ValueError):
        scene.simulate(method="euler")
    with pytest.raises(ValueError):
        scene.simulate(until=-1)
    with pytest.raises(OSError):
        lagrange.load(EXAMPLES / "no_such_scene.lag")


def test_notebook_display_is_latex():
    d = lagrange.load(EXAMPLES / "ps5" / "falling_rod.lag").derive()
    latex = d._repr_latex_()
    assert isinstance(latex, str)
    assert latex.startswith("$$") and "\\begin{aligned}" in latex
    assert "\\ddot{\\theta}" in latex and "\\frac{12 g}{7 L}" in latex


def test_kept_constraint_has_multiplier_and_numbers_hold_it():
    scene = lagrange.load(EXAMPLES / "classics" / "pendulum_cartesian.lag")
    d = scene.derive()
    assert len(d.multipliers) == 1
    assert any(c.handling == "kept" for c in d.constraints)
    f = scene.rhs()
    out = f(0.0, f.y0)
    assert out.shape == (len(f.names),) and np.all(np.isfinite(out))


@pytest.mark.parametrize(
    "path", sorted(EXAMPLES.glob("**/*.lag")), ids=lambda p: f"{p.parent.name}/{p.stem}"
)
def test_every_example_derives_evaluates_and_checks(path):
    scene = lagrange.load(path)
    d = scene.derive()
    n = len(d.coordinates)
    assert d.mass_matrix.shape == (n, n) and d.forcing.shape == (n, 1)
    assert len(d.equations) >= 1 and "\\begin{aligned}" in d._repr_latex_()
    names = [str(q.func) for q in d.coordinates]
    if re.search(r"^contact ", path.read_text(encoding="utf-8"), re.MULTILINE):
        # A right-hand side would hold every contact closed: it refuses, naming them; a run
        # takes them.
        with pytest.raises(ValueError, match=r"does not take contacts yet.*`"):
            scene.rhs()
        try:
            run = scene.simulate(until=1e-3, samples=2, output=names)
        except lagrange.NumericError as fault:
            # Painlevé's rods (in the plane, in space) start where rigid bodies with Coulomb
            # friction have no motion: the run ends at once, naming the case.
            assert "Painlevé" in str(fault) and path.stem.startswith("painleve_rod"), fault
            assert fault.results.contacts == ["floor"]
        else:
            assert run.contacts and len(run.t) >= 2
            q0 = [run[name][0] for name in names]
            assert np.all(np.isfinite(scene.mass_matrix_function()(0.0, q0)))
    else:
        f = scene.rhs()
        assert f.names[:n] == names
        assert np.all(np.isfinite(f(0.0, f.y0)))
        assert scene.mass_matrix_function()(0.0, f.y0).shape == (n, n)
    assert all(e.held for e in scene.check())


def test_chaplygin_sleigh_has_equations_in_the_independent_rates():
    d = lagrange.load(EXAMPLES / "classics" / "chaplygin_sleigh.lag").derive()
    form = d.independent
    assert form is not None
    assert len(form["equations"]) == len(form["independent"])
    assert form["dependent"] and all(isinstance(e, sp.Eq) for e in form["equations"])


def test_linearize_the_pendulum_and_sweep_the_sleeping_top():
    pendulum = lagrange.load(EXAMPLES / "classics" / "simple_pendulum.lag")
    hanging = pendulum.linearize(about="theta = 0")
    g, L = sp.symbols("g L")
    m = sp.Symbol("m")
    assert sp.simplify(hanging["K"][0, 0] - m * L * g) == 0
    omega = np.sqrt(9.81 / 1.0)
    assert np.allclose(sorted(hanging["eigenvalues"].imag), [-omega, omega], rtol=1e-12)
    assert hanging["stability"] == "marginally stable"
    standing = pendulum.linearize(about={"theta": "pi"})
    assert standing["stability"] == "unstable"

    top = lagrange.load(EXAMPLES / "space" / "sleeping_top.lag")
    swept = top.linearize(sweep="w=0:100:11")
    changes = swept["sweep"]["changes"]
    assert len(changes) == 1
    assert abs(changes[0]["value"] - 51.1468474101777) < 1e-6
    with pytest.raises(lagrange.SceneError):
        pendulum.linearize(about="theta = 1")


def test_the_cart_pole_state_space_for_a_controller():
    scene = lagrange.load(EXAMPLES / "classics" / "inverted_pendulum_on_cart.lag")
    lin = scene.linearize()
    assert lin.state == ["x", "theta", "x'", "theta'"]
    assert lin.inputs == ["F"] and lin.outputs == ["position", "tip"]
    M, m, L, g = sp.symbols("M m L g")
    # The hand derivation, exactly: det M = M·m·L².
    hand_a = sp.Matrix(
        [[0, 0, 1, 0], [0, 0, 0, 1], [0, -m * g / M, 0, 0], [0, (M + m) * g / (M * L), 0, 0]]
    )
    assert lin.exact
    assert sp.simplify(lin.A_sym - hand_a) == sp.zeros(4, 4)
    assert sp.simplify(lin.B_sym - sp.Matrix([0, 0, 1 / M, -1 / (M * L)])) == sp.zeros(4, 1)
    assert lin.C_sym == sp.Matrix([[1, 0, 0, 0], [1, L, 0, 0]])
    values = {M: 2, m: 1, L: 1, g: 9.81}
    assert np.allclose(lin.A, np.array(hand_a.subs(values), dtype=float), rtol=1e-14)
    assert np.allclose(lin.B[:, 0], [0, 0, 0.5, -0.5], rtol=1e-14)
    assert lin.controllability["rank"] == 4 and lin.observability["rank"] == 4
    # The dict it always was, and the cyclic position left out on request.
    assert lin["stability"] == "unstable" and lin["cyclic_zeros"] == 1
    dropped = scene.linearize(keep_cyclic=False, outputs=["tip"])
    assert dropped.state == ["theta", "x'", "theta'"]
    assert dropped.C.shape == (1, 3) and dropped.D.shape == (1, 1)
    with pytest.raises(ValueError) as caught:
        scene.linearize(inputs=["G"])
    assert "no input 'G'" in str(caught.value)
    try:
        import control
    except ImportError:
        with pytest.raises(ImportError):
            lin.to_control()
    else:
        ss = lin.to_control()
        assert isinstance(ss, control.StateSpace)
        assert np.allclose(ss.A, lin.A) and np.allclose(ss.B, lin.B)


def test_settings_are_named_as_python_callers_write_them():
    scene = lagrange.load(EXAMPLES / "classics" / "simple_pendulum.lag")
    with pytest.raises(ValueError) as caught:
        scene.simulate(until=-1)
    assert str(caught.value).startswith("`until` must be a positive time"), caught.value
    with pytest.raises(ValueError) as caught:
        scene.simulate(until=0.1, set={"gg": 1})
    message = str(caught.value)
    assert message.startswith('`set={"gg": …}`: no parameter or coordinate'), message
    assert "--" not in message
    with pytest.raises(ValueError) as caught:
        scene.linearize(about="theta=0", sweep="w=0:1:3")
    assert str(caught.value).startswith('`sweep="w"`: no parameter'), caught.value
    with pytest.raises(ValueError) as caught:
        scene.linearize()
    assert '`about="theta=0"`' in str(caught.value), caught.value


def test_str_of_a_scene_error_keeps_the_hint():
    text = "param length = 2\ncoord x = 0\nparticle p { mass 1; position (x, 0) }\npotential lenght*x\n"
    with pytest.raises(lagrange.SceneError) as caught:
        lagrange.loads(text)
    assert "did you mean `length`?" in str(caught.value), str(caught.value)


def test_samples_counts_times_as_linspace_does():
    scene = lagrange.load(EXAMPLES / "classics" / "simple_pendulum.lag")
    run = scene.simulate(until=2.0, samples=5)
    np.testing.assert_allclose(run["t"], np.linspace(0.0, 2.0, 5), atol=1e-12)
    with pytest.raises(ValueError, match="`samples` must be 0"):
        scene.simulate(until=1.0, samples=-1)
    with pytest.raises(TypeError):
        scene.simulate(until=1.0, samples=2.5)


def test_the_callables_and_the_version_are_exported():
    scene = lagrange.load(EXAMPLES / "classics" / "simple_pendulum.lag")
    assert isinstance(scene.rhs(), lagrange.Rhs)
    assert isinstance(scene.mass_matrix_function(), lagrange.MassMatrix)
    assert {"Rhs", "MassMatrix", "__version__"} <= set(lagrange.__all__)
    assert lagrange.__version__ == importlib.metadata.version("lagrange")
    assert lagrange.__version__[0].isdigit()


def test_the_stub_covers_the_native_module():
    package = Path(lagrange.__file__).parent
    assert (package / "py.typed").is_file()
    stub = ast.parse((package / "_native.pyi").read_text(encoding="utf-8"))
    declared = {
        node.name
        for node in stub.body
        if isinstance(node, (ast.ClassDef, ast.FunctionDef))
    }
    native = {name for name in dir(lagrange._native) if not name.startswith("_")}
    assert declared == native
    # Each class's public methods and attributes, too.
    for node in stub.body:
        if isinstance(node, ast.ClassDef):
            members = {
                item.name if isinstance(item, ast.FunctionDef) else item.target.id
                for item in node.body
                if isinstance(item, (ast.FunctionDef, ast.AnnAssign))
            }
            real = {m for m in dir(getattr(lagrange._native, node.name)) if not m.startswith("_")}
            assert {m for m in members if not m.startswith("_")} == real, node.name


def test_mypy_accepts_a_typed_use_of_the_package(tmp_path):
    mypy = pytest.importorskip("mypy.api")
    script = tmp_path / "use.py"
    script.write_text(
        "import lagrange\n"
        "scene = lagrange.loads('coord x = 0\\nparticle p { mass 1; position (x, 0) }\\n')\n"
        "f: lagrange.Rhs = scene.rhs()\n"
        "names: list[str] = f.names\n"
        "n: int = lagrange._native.loads('')\n",
        encoding="utf-8",
    )
    out, err, status = mypy.run([str(script), "--no-error-summary"])
    # The last line is wrong on purpose: mypy must see the stub to catch it.
    assert status == 1, out + err
    assert "use.py:5" in out and "NativeScene" in out, out
    assert out.count("error:") == 1, out


def test_auto_reports_where_each_method_ran():
    stiff = lagrange.load(EXAMPLES / "classics" / "stiff_spring_pendulum.lag")
    results = stiff.simulate(method="auto", set={"k": 1e10})
    assert results.method == "auto"
    methods = [method for method, _, _ in results.segments]
    assert methods == ["dop853", "radau"]
    (_, start, switch), (_, again, end) = results.segments
    assert start == 0.0 and switch == again and end == 10.0
    # One method, one segment over the whole run.
    plain = stiff.simulate(method="radau", set={"k": 1e10})
    assert plain.segments == [("radau", 0.0, 10.0)]
