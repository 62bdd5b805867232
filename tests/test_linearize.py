"""Linear models of FMUs (analysis.linearize) against closed forms: the hanging chain of point
masses (Laguerre's zeros), one rod, the continuous chain (Bernoulli's Bessel zeros), sympy's
own KanesMethod.linearize, joint damping, an FMU run at small amplitude, differences of runs;
and FMUs this project did not build (the Modelica Reference FMUs' VanDerPol and StateSpace)."""

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.special import jn_zeros, roots_laguerre

from conical_pendulum import Link, Scene
from conical_pendulum.analysis.fmpy_runs import run_fmu
from conical_pendulum.analysis.linearize import LinearModel, color_columns, describe_modes, linearize
from conical_pendulum.errors import UserError

G, L, M_BOB = 9.8, 10.0, 5.0  # the scenes' defaults: gravity, link length, bob mass
HANGING = {"alpha*": 0.0, "beta*": 0.0}  # the hanging equilibrium (the FMUs start at 10 degrees)
# ../shared beside the checkout, or beside a folder above it (a work tree), or /work's
REFERENCE = next(
    (
        found
        for folder in (*Path(__file__).resolve().parents[2:], Path("/work"))
        if (found := folder / "shared" / "fmus" / "reference-fmus").is_dir()
    ),
    Path("../shared/fmus/reference-fmus"),
)
SETTINGS = {"solver": 2, "rtol": 1e-12, "atol": 1e-12}  # DOP853


def reference_fmu(version, name):
    path = REFERENCE / version / f"{name}.fmu"
    if not path.exists():
        if os.environ.get("CI") == "true":
            pytest.fail(f"{path} is missing (the Modelica Reference FMUs, ../shared/fmus)")
        pytest.skip(f"{path} is missing (the Modelica Reference FMUs, ../shared/fmus)")
    return path


def frequencies(model):
    """Every mode's natural frequency in rad/s (each complex pair once), ascending."""
    return np.sort([mode.rad_per_s for mode in model.modes()])


def laguerre_zeros(n):
    """The zeros of L_n: scipy's, polished by Newton's method in 40-digit arithmetic on the
    three-term recurrence (k + 1) L_k+1 = (2k + 1 - x) L_k - k L_k-1, x L_n' = n (L_n - L_n-1)."""
    import mpmath

    with mpmath.workdps(40):

        def newton_step(x):
            before, value = mpmath.mpf(1), 1 - x
            for k in range(1, n):
                before, value = value, ((2 * k + 1 - x) * value - k * before) / (k + 1)
            return value / (n * (value - before) / x)

        zeros = []
        for x in roots_laguerre(n)[0]:
            x = mpmath.mpf(x)
            for _ in range(8):
                x -= newton_step(x)
            zeros.append(float(x))
    return np.array(zeros)


@pytest.mark.parametrize("n", [1, 2, 3, 10, 100])
def test_point_masses_on_massless_links_hang_at_laguerres_zeros(built_fmu, n):
    """omega_k^2 = (g/l) x_k, x_k the zeros of L_n, each twice (two planes); from the
    directional derivatives, to 1e-9 (measured: up to 2e-13 at n = 100)."""
    path = built_fmu(Scene.uniform(n, massless_links=True), backend="native")
    model = linearize(path, states=HANGING)
    expected = np.repeat(np.sqrt(G / L * laguerre_zeros(n)), 2)
    found = frequencies(model)
    assert len(found) == 2 * n
    assert np.abs(found / expected - 1).max() < 1e-9
    # undamped: each real part is rounding (below n eps ||A||), and the ratio reads 0, not -6e-17
    assert all(mode.damping_ratio == 0.0 for mode in model.modes())
    if n == 2:  # the numbers: 0.7654 and 1.8478 sqrt(g/l)
        np.testing.assert_allclose(found[::2] / math.sqrt(G / L), [0.7654, 1.8478], atol=5e-5)


def test_the_fmi3_fmu_gives_the_same_model(built_fmu):
    """FMI 3.0's arrays named as FMI 2.0's scalars: the same states and inputs in the same
    order, the same outputs in its ModelStructure's order (array by array), the same numbers."""
    scene = Scene.uniform(3, massless_links=True)
    two = linearize(built_fmu(scene, backend="native"), states=HANGING)
    three = linearize(built_fmu(scene, backend="native", fmi_version=3), states=HANGING)
    assert (two.states, two.inputs) == (three.states, three.inputs)
    assert sorted(two.outputs) == sorted(three.outputs)
    rows = [two.outputs.index(name) for name in three.outputs]
    for name, two_part in (("A", two.A), ("B", two.B), ("C", two.C[rows]), ("D", two.D[rows])):
        np.testing.assert_allclose(getattr(three, name), two_part, rtol=0, atol=1e-13)


def test_one_rod_hinged_at_its_end(built_fmu):
    """A thin uniform rod: omega^2 = 3 g / (2 l); a cylinder of radius r: omega^2 = (M g l/2) /
    (M (3 r^2 + l^2)/12 + M l^2/4); each twice, to 1e-12."""
    link = Link(has_bob=False)
    path = built_fmu(Scene(links=(link,)), backend="native")
    thin = link.mass * link.length**2 / 12
    model = linearize(path, states=HANGING, parameters={"Ixx0": thin, "Izz0": thin})
    np.testing.assert_allclose(frequencies(model), [math.sqrt(1.5 * G / L)] * 2, rtol=1e-12)
    cylinder = linearize(path, states=HANGING)
    end = link.mass * (3 * link.radius**2 + link.length**2) / 12 + link.mass * link.length**2 / 4
    omega = math.sqrt(link.mass * G * link.length / 2 / end)
    np.testing.assert_allclose(frequencies(cylinder), [omega] * 2, rtol=1e-12)


def rods(n, length=L, mass=10.0):
    """n thin uniform rods, one chain of total length and mass as given, no bobs."""
    each, m = length / n, mass / n
    thin = m * each**2 / 12
    return Scene(links=(Link(has_bob=False, length=each, mass=m, moments=(thin, 0.0, thin)),) * n)


def test_a_chain_of_rods_approaches_the_continuous_chain(built_fmu):
    """The continuous hanging chain's omega_k = (j_0,k / 2) sqrt(g / L). A chain of n thin rigid
    rods is the linear finite-element Galerkin model of it (a rod's small displacement is linear
    along it, its kinetic energy is the consistent mass matrix's, its potential the tension's
    integral of the slope squared, exactly): its frequencies are Rayleigh-Ritz upper bounds and
    their relative error falls as 1/n^2. So, for the lowest three at n = 12, 24, 48: every one
    above the continuous chain's; the error falling by 3.5 to 4.5 when n doubles (measured 3.61
    to 3.99); and the limit the sequence tends to, Richardson's (4 f(48) - f(24)) / 3, the
    continuous chain's to a tenth of the error at n = 48 (measured: 0.3 %, 1.6 %, 6 % of it),
    which a chain converging to anything else would miss. (At n = 48: 1.3e-5, 4.5e-4, 1.9e-3.)"""
    expected = jn_zeros(0, 3) / 2 * math.sqrt(G / L)
    found = {}
    for n in (12, 24, 48):
        found[n] = frequencies(linearize(built_fmu(rods(n), backend="native"), states=HANGING))[::2][:3]
        assert (found[n] > expected).all(), (n, found[n] / expected - 1)
    errors = [found[n] / expected - 1 for n in (12, 24, 48)]
    ratios = np.array([errors[0] / errors[1], errors[1] / errors[2]])
    assert ((ratios > 3.5) & (ratios < 4.5)).all(), ratios
    limit = (4 * found[48] - found[24]) / 3
    assert (np.abs(limit / expected - 1) < 0.1 * errors[2]).all(), (limit / expected - 1, errors[2])


# slow: sympy's linearization of the seed takes 2 to 4 minutes; it is the one check of A against a
# linearizer nobody here wrote (the others are closed forms of one or two links)
@pytest.mark.slow
def test_the_seeds_a_is_sympys_kanesmethod_linearize(built_fmu):
    """The seed scene's A at the hanging equilibrium against sympy's own KanesMethod.linearize
    of the same construction (builder.core.kane.chain), M [q' u'] = A [q u] at q = u = q' = u' = 0
    with the parameters as symbols, to 1e-10 of A's largest entry (measured: 5e-15)."""
    import sympy as sm
    import sympy.physics.mechanics as me

    from conical_pendulum.builder.core.kane import chain

    scene = Scene.uniform(3)
    p = {name: sm.Symbol(name) for name in scene.core_parameter_names()}
    frame, pivot = me.ReferenceFrame("I"), me.Point("O")
    pivot.set_vel(frame, 0)
    bodies, loads, q, u, kd = chain(scene, frame, pivot, p)
    kane = me.KanesMethod(frame, q_ind=q, u_ind=u, kd_eqs=kd)
    kane.kanes_equations(bodies, loads)
    at_rest = dict.fromkeys(q + u, 0) | {s.diff(): 0 for s in q + u}
    mass, forcing = kane.linearize(A_and_B=False, op_point=at_rest)[:2]
    evaluate = sm.lambdify([p[name] for name in scene.parameter_names()], [mass, forcing], cse=True)
    m, a = (np.array(x, dtype=float) for x in evaluate(*scene.parameter_defaults()))
    expected = np.linalg.solve(m, a)
    model = linearize(built_fmu(scene, backend="native"), states=HANGING)
    assert model.states == [str(s).removesuffix("(t)") for s in q + u]
    assert np.abs(model.A - expected).max() < 1e-10 * np.abs(expected).max()


def test_joint_damping_moves_the_eigenvalues_off_the_axis_as_it_says(built_fmu):
    """One bob on a massless link with joint damping c: m l^2 theta'' + c theta' + m g l theta
    = 0, lambda = -c / (2 m l^2) +- sqrt((c / (2 m l^2))^2 - g / l) in each plane: damping ratio
    c / (2 m l^2 sqrt(g/l)) at the natural frequency sqrt(g/l), underdamped and overdamped; the
    work of the damping (a state) is a zero eigenvalue."""
    scene = Scene(links=(Link(has_mass=False, damping=1.0),), joint_damping=True)
    path = built_fmu(scene, backend="native")
    for c in (100.0, 2000.0):
        model = linearize(path, states=HANGING, parameters={"c0": c})
        decay = c / (2 * M_BOB * L**2)
        expected = -decay + np.sqrt(complex(decay**2 - G / L)) * np.array([1, -1, 1, -1])
        found = np.linalg.eigvals(model.A)
        assert np.isclose(found, 0, atol=1e-12).sum() == 1  # W_damping
        assert model.modes()[0].components == (("W_damping", 1.0),)  # it moves no angle
        found = found[np.abs(found) > 1e-9]
        np.testing.assert_allclose(np.sort_complex(found), np.sort_complex(expected), rtol=1e-10)
        # how stiff: the decaying modes' |Re lambda| from slowest to fastest (W_damping's 0 is
        # no decaying mode), and the fastest |lambda|
        stiffness = model.stiffness()
        assert stiffness.ratio == pytest.approx(expected.real.min() / expected.real.max(), rel=1e-9)
        assert abs(stiffness.fastest) == pytest.approx(np.abs(expected).max(), rel=1e-10)
        if c < 2 * M_BOB * L**2 * math.sqrt(G / L):
            mode = model.modes()[-1]
            assert mode.damping_ratio == pytest.approx(decay / math.sqrt(G / L), rel=1e-10)
            assert mode.rad_per_s == pytest.approx(math.sqrt(G / L), rel=1e-10)


def test_the_lowest_frequency_is_a_small_swings(built_fmu):
    """The seed swung in its lowest planar mode at 1e-3 rad: its period, from alpha0's zero
    crossings over 60 s of the FMU's own run (DOP853 at 1e-12), gives the linear model's lowest
    frequency to 1e-5 (the nonlinear shift is of order the amplitude squared, 1e-6)."""
    scene = Scene.uniform(3)
    path = built_fmu(scene, backend="native")
    model = linearize(path, states=HANGING)
    plane = [model.states.index(f"{s}{i}") for s in ("alpha", "omega") for i in range(3)]
    values, vectors = np.linalg.eig(model.A[np.ix_(plane, plane)])
    lowest = np.argmin(np.abs(values))
    shape = np.real(vectors[:3, lowest] / vectors[0, lowest])
    start = {f"alpha{i}": 1e-3 * shape[i] for i in range(3)} | {f"beta{i}": 0.0 for i in range(3)}
    run = run_fmu(path, stop_time=60.0, output_interval=0.01, start_values={**SETTINGS, **start})
    t, angle = run["time"], run["alpha0"]
    k = np.nonzero(np.sign(angle[:-1]) != np.sign(angle[1:]))[0]
    crossings = t[k] - angle[k] * (t[k + 1] - t[k]) / (angle[k + 1] - angle[k])
    measured = math.pi * (len(crossings) - 1) / (crossings[-1] - crossings[0])
    assert measured == pytest.approx(abs(values[lowest].imag), rel=1e-5)
    assert abs(values[lowest].imag) == pytest.approx(frequencies(model)[0], rel=1e-12)


FORCED = Scene(links=(Link(), Link(bob_force=True), Link()), air_drag=True, coupling=True)


@pytest.mark.parametrize(
    ("scene", "name", "at"),
    [
        (Scene.uniform(3, coupling=True), "a_pivot_x", 0.0),
        (Scene.uniform(3, coupling=True), "a_pivot_z", 0.0),
        (FORCED, "wind_x", 3.0),
        (FORCED, "wind_z", -2.0),
        (FORCED, "F_bob1_x", 0.0),
        (FORCED, "F_bob1_z", 0.0),  # F_bob1_y: along the hanging links, a zero column
    ],
)
def test_b_columns_are_differences_of_runs(built_fmu, scene, name, at):
    """B's column of an input against runs of the FMU with the input held at at +- 1e-3: the
    states' central difference S(t) = dx(t)/du is B t + O(t^2); a polynomial of degree 6 through
    0 fitted to S at t = 0.01 ... 0.08 s gives its slope at 0 to about 1e-7 of the column (the
    runs' errors over 1e-3, the t^7 term), checked to 1e-6. In a wind: the drag's derivative."""
    path = built_fmu(scene, backend="native")
    model = linearize(path, states=HANGING, inputs={name: at})
    column = model.B[:, model.inputs.index(name)]
    start = {**SETTINGS, **{f"{s}{i}": 0.0 for s in ("alpha", "beta") for i in range(scene.n)}}
    if name.startswith("wind"):
        start[name] = at  # the other inputs held at their starts, 0, as in the model
    runs = [
        run_fmu(path, stop_time=0.08, output_interval=0.01, start_values={**start, name: at + h})
        for h in (1e-3, -1e-3)
    ]
    t = runs[0]["time"][1:]
    sensitivity = np.array([(runs[0][s][1:] - runs[1][s][1:]) / 2e-3 for s in model.states]).T
    powers = np.vander(t, 7, increasing=True)[:, 1:]
    slope = np.linalg.lstsq(powers, sensitivity, rcond=None)[0][0]
    assert np.abs(column).max() > 0
    assert np.abs(slope - column).max() < 1e-6 * np.abs(column).max()


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_van_der_pol_exactly(version):
    """VanDerPol: x0' = x1, x1' = mu (1 - x0^2) x1 - x0, so A = [[0, 1], [-2 mu x0 x1 - 1,
    mu (1 - x0^2)]] at every state and mu; directional derivatives to rounding, differences
    within their error estimate (and it below 1e-6)."""
    path = reference_fmu(version, "VanDerPol")
    for x0, x1, mu in ((2.0, 0.0, 1.0), (1.5, -0.5, 1.0), (-0.3, 2.0, 2.5)):
        expected = np.array([[0.0, 1.0], [-2 * mu * x0 * x1 - 1, mu * (1 - x0**2)]])
        exact = linearize(path, states={"x0": x0, "x1": x1}, parameters={"mu": mu})
        assert exact.method == "directional" and exact.calls == 2
        np.testing.assert_allclose(exact.A, expected, rtol=0, atol=1e-14)
        np.testing.assert_array_equal(exact.C, np.eye(2))  # its outputs are its states
        differences = linearize(
            path, states={"x0": x0, "x1": x1}, parameters={"mu": mu}, method="differences"
        )
        assert differences.error.max() < 1e-6
        assert (np.abs(differences.A - expected) <= differences.error[:2, :2]).all()


def test_state_space_is_its_own_parameters():
    """StateSpace (FMI 3.0, no directional derivatives): A, B, C, D are its parameters, set as
    arrays; by differences, within their error estimate (exact but for rounding: it is linear)."""
    path = reference_fmu("3.0", "StateSpace")
    rng = np.random.default_rng(1)
    given = {name: rng.standard_normal((3, 3)) for name in "ABCD"}
    model = linearize(path, parameters={k: v.ravel() for k, v in given.items()}, inputs={"u": [0.5, -1, 2]})
    assert model.method == "differences"
    with pytest.raises(UserError, match=r"gives no directional derivatives.*use method 'differences'"):
        linearize(path, method="directional")
    assert model.states == ["x[1]", "x[2]", "x[3]"] and model.inputs == ["u[1]", "u[2]", "u[3]"]
    for name, matrix in given.items():
        part = getattr(model, name)
        np.testing.assert_allclose(part, matrix, rtol=0, atol=1e-9)
    assert (
        np.abs(
            np.block([[model.A, model.B], [model.C, model.D]])
            - np.block([[given["A"], given["B"]], [given["C"], given["D"]]])
        )
        <= model.error
    ).all()


@pytest.mark.parametrize("version", [2, 3])
def test_the_cart(built_cart, version):
    """The coupled demo's cart: (m + M_x) v' = F_x - k x - c v, its acceleration an output."""
    model = linearize(built_cart(version), states={"x": 0.4, "v": -0.3}, inputs={"F_x": 12.0, "M_x": 7.0})
    k, c, mass = 150.0, 20.0, 100.0 + 7.0  # the cart's defaults, and M_x
    a = (12.0 - k * 0.4 - c * -0.3) / mass
    np.testing.assert_allclose(model.A, [[0, 1], [-k / mass, -c / mass]], rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(model.B, [[0, 0], [1 / mass, -a / mass]], rtol=1e-13, atol=1e-15)
    row = model.outputs.index("a")
    np.testing.assert_allclose(model.C[row], [-k / mass, -c / mass], rtol=1e-13)
    np.testing.assert_allclose(model.D[row], [1 / mass, -a / mass], rtol=1e-13)


def test_grouping_by_sparsity():
    """Curtis, Powell and Reid: columns sharing no row share a call; an empty column none."""
    tridiagonal = np.eye(9, dtype=bool) | np.eye(9, k=1, dtype=bool) | np.eye(9, k=-1, dtype=bool)
    assert color_columns(tridiagonal) == [[0, 3, 6], [1, 4, 7], [2, 5, 8]]
    with_empty = np.array([[1, 0, 1], [0, 0, 1]], dtype=bool)
    assert color_columns(with_empty) == [[0], [2]]


def test_grouped_calls_give_the_same_numbers(built_fmu):
    """A damped chain: every column meets every other in the angular accelerations, so no two
    share a call, and its books' state W_damping, on which nothing depends, costs none; grouped
    or not, the same matrices bit for bit."""
    scene = Scene(links=(Link(damping=2.0), Link(damping=1.0)), joint_damping=True)
    path = built_fmu(scene, backend="native")
    grouped = linearize(path, states=HANGING)
    single = linearize(path, states=HANGING, grouped=False)
    for name in "ABCD":
        np.testing.assert_array_equal(getattr(grouped, name), getattr(single, name))
    assert grouped.calls == single.calls == len(scene.state_names()) - 1


def test_groups_of_columns_share_a_call(tmp_path):
    """StateSpace with B = C = 0, its ModelStructure saying so (der(x) on x, y on u: FMI 3.0
    lists whole arrays): x[k] and u[k] share a call, 3 groups instead of 6 columns, and each
    entry lands in its own column: A and D as given, B and C zero."""
    import zipfile

    source = reference_fmu("3.0", "StateSpace")
    path = tmp_path / "StateSpaceSparse.fmu"
    with zipfile.ZipFile(source) as original, zipfile.ZipFile(path, "w") as copy:
        for item in original.infolist():
            data = original.read(item)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                for vr, depends in (("10", "9"), ("12", "11")):  # y on u, der(x) on x
                    tag = "Output" if vr == "10" else "ContinuousStateDerivative"
                    old = f'<{tag} valueReference="{vr}"/>'
                    assert old in text
                    text = text.replace(old, f'<{tag} valueReference="{vr}" dependencies="{depends}"/>')
                data = text.encode()
            copy.writestr(item, data)
    rng = np.random.default_rng(2)
    given = {"A": rng.standard_normal((3, 3)), "B": np.zeros((3, 3)), "C": np.zeros((3, 3))}
    given["D"] = rng.standard_normal((3, 3))
    parameters = {k: v.ravel() for k, v in given.items()}
    grouped = linearize(path, parameters=parameters, inputs={"u": [1.0, -2.0, 0.5]})
    single = linearize(path, parameters=parameters, inputs={"u": [1.0, -2.0, 0.5]}, grouped=False)
    assert (grouped.calls, single.calls) == (4 * 3, 4 * 6)  # differences: 4 evaluations a group
    for name, matrix in given.items():
        np.testing.assert_allclose(getattr(grouped, name), matrix, rtol=0, atol=1e-9)
        np.testing.assert_allclose(getattr(grouped, name), getattr(single, name), rtol=0, atol=1e-12)


def test_files_and_python_control(built_fmu, tmp_path):
    """.npz and .mat carry the matrices and the names; python-control's StateSpace has the
    same poles and signal names."""
    from scipy.io import loadmat

    model = linearize(built_fmu(Scene.uniform(3, coupling=True), backend="native"), states=HANGING)
    data = np.load(model.save(tmp_path / "seed.npz"))
    np.testing.assert_array_equal(data["A"], model.A)
    assert list(data["inputs"]) == model.inputs == ["a_pivot_x", "a_pivot_y", "a_pivot_z"]
    mat = loadmat(model.save(tmp_path / "seed.mat"))
    np.testing.assert_array_equal(mat["B"], model.B)
    assert [str(s[0]) for s in mat["states"].ravel()] == model.states
    system = model.to_control()
    assert list(system.state_labels) == model.states and list(system.output_labels) == model.outputs
    np.testing.assert_allclose(np.sort_complex(system.poles()), np.sort_complex(np.linalg.eigvals(model.A)))
    lines = describe_modes(model.modes())
    assert "rad/s" in lines[0] and "alpha0" in " ".join(lines)
    with pytest.raises(UserError, match=r"a \.npz or a \.mat"):
        model.save(tmp_path / "seed.csv")


def test_refusals_say_what_to_do(built_fmu):
    """An FMU with no Model Exchange (the pythonfmu FMU) is refused naming the native build;
    unknown names and non-finite values name themselves."""
    with pytest.raises(UserError, match=r"no Model Exchange.*conical-pendulum build --native"):
        linearize(built_fmu(Scene.uniform(3)))
    path = built_fmu(Scene.uniform(3), backend="native")
    with pytest.raises(UserError, match=r"state 'gamma0'.*has no state by that name; it has alpha0"):
        linearize(path, states={"gamma0": 0.0})
    with pytest.raises(UserError, match="state 'alpha0': must be finite"):
        linearize(path, states={"alpha0": float("nan")})
    with pytest.raises(UserError, match="parameter 'q'"):
        linearize(path, parameters={"q": 1.0})
    with pytest.raises(UserError, match="method: 'exact'"):
        linearize(path, method="exact")
    with pytest.raises(UserError, match="time: must be finite"):
        linearize(path, time=float("inf"))


def command(*args):
    return subprocess.run(
        [sys.executable, "-m", "conical_pendulum", "linearize", *map(str, args)],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
        stdin=subprocess.DEVNULL,
    )


def test_stiffness_is_the_decaying_modes_spread_and_the_fastest_mode():
    """A diagonal A with -1 and -1000 and an undamped pair +-10i: ratio 1000, the fastest
    mode the pair's or the decay's, whichever is larger; no decaying mode: no ratio."""
    A = np.zeros((4, 4))
    A[0, 0], A[1, 1], A[2, 3], A[3, 2] = -1.0, -1000.0, 10.0, -10.0

    def model(A):
        return LinearModel(
            A, np.zeros((4, 0)), np.zeros((0, 4)), np.zeros((0, 0)), list("abcd"), [], [],
            np.zeros(4), np.zeros(0), np.zeros(0), np.zeros(4), 0.0, "directional", 0, "",
        )  # fmt: skip

    stiffness = model(A).stiffness()
    assert stiffness.ratio == pytest.approx(1000.0) and stiffness.fastest == pytest.approx(-1000.0)
    assert (
        stiffness.time_scale == pytest.approx(1e-3)
        and "stiff: choose solver radau or auto" in stiffness.describe()
    )
    A[0, 0] = A[1, 1] = 0.0
    undamped = model(A).stiffness()
    assert undamped.ratio is None and abs(undamped.fastest) == pytest.approx(10.0)
    assert "no decaying mode, not stiff" in undamped.describe()


def test_the_command(built_fmu, tmp_path):
    """`conical-pendulum linearize`: modes printed, files and the mode shapes written; a bad
    name, or mode shapes of an FMU that is no chain of this project's, is one line."""
    path = built_fmu(Scene.uniform(3), backend="native")
    out, picture = tmp_path / "seed.mat", tmp_path / "modes.png"
    hanging = ["--state", "alpha*=0", "--state", "beta*=0"]
    done = command(path, *hanging, "--out", out, "--out", tmp_path / "seed.npz", "--plot", picture)
    assert done.returncode == 0, done.stderr
    assert "0.666647" in done.stdout and "directional" in done.stdout
    assert "fastest mode |lambda| = " in done.stdout and "no decaying mode, not stiff" in done.stdout
    assert out.exists() and (tmp_path / "seed.npz").exists() and picture.stat().st_size > 10000
    for args, said in (
        ([path, "--state", "gamma=1"], "state 'gamma'"),
        ([reference_fmu("2.0", "VanDerPol"), "--plot", picture], "--plot: draws this project's chains only"),
        ([path, "--out", tmp_path / "seed.csv"], "a .npz or a .mat file"),
    ):
        bad = command(*args)
        assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1, bad.stderr
        assert said in bad.stderr


@pytest.mark.filterwarnings("error")
def test_a_free_bodys_repeated_zero_eigenvalues_give_one_mode_per_direction():
    """A double integrator in two planes (A a Jordan block per plane, as a chain's angles where
    gravity holds nothing): numpy's eigenvectors for the fourfold 0 are two directions and two
    near-copies, which carry only rounding once the directions are taken out. Two modes, one
    per plane, no division by a vanished pivot."""
    states = ["a", "b", "omega_a", "omega_b"]
    A = np.array([[0.0, 0, 1, 0], [0, 0, 0, 1], [0, 0, 0, 0], [0, 0, 0, 0]])
    empty = np.zeros(0)
    model = LinearModel(
        A, np.zeros((4, 0)), np.zeros((0, 4)), np.zeros((0, 0)), states, [], [],
        np.zeros(4), empty, empty, np.zeros(4), 0.0, "directional", 0, "double integrator",
    )  # fmt: skip
    assert [mode.components for mode in model.modes()] == [(("a", 1.0),), (("b", 1.0),)]
