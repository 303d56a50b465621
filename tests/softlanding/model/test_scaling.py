import math

import pytest

from softlanding import (
    Impact,
    Impedance,
    ParameterError,
    PhysicalParams,
    Robot,
    Units,
    paper_rig,
)


def test_paper_rig_scales_to_paper_numbers():
    robot, impact, _, _ = paper_rig().to_dimensionless()
    assert robot.r_m == pytest.approx(5.0)
    assert robot.s == pytest.approx(20.0)
    assert robot.u_max == pytest.approx(8.2)
    # velocity scale sqrt(g^2 m_t / k_g): 1.2 m/s is v0 = -4.68 (the paper says -4.8)
    assert impact.v0 == pytest.approx(-1.2 / math.sqrt(9.81**2 * 3.0 / 4400.0))


def test_round_trip_both_ways():
    ph = PhysicalParams(m_b=7.0, m_f=1.3, k_g=12_000.0, stroke=0.2, v0=-2.0, u_max=500.0,
                        K_p=3000.0, K_d=150.0)
    robot, impact, imp, _ = ph.to_dimensionless()
    back = PhysicalParams.from_dimensionless(robot, impact, ph.units, imp)
    for name in ("m_b", "m_f", "k_g", "stroke", "v0", "u_max", "K_p", "K_d"):
        assert getattr(back, name) == pytest.approx(getattr(ph, name), rel=1e-12)
    d = {"r_m": 3, "s": 12, "v0": -4, "u_max": 6, "k_p": 0.3, "k_d": 0.2}
    again = PhysicalParams.from_dimensionless(
        Robot(r_m=3, s=12, u_max=6), Impact(-4), Units(10.0, 5000.0),
        Impedance(0.3, 0.2)).to_dimensionless()
    got = {**again.robot.to_dict(), **again.impact.to_dict(), "k_p": again.controller.k_p,
           "k_d": again.controller.k_d}
    for name in ("r_m", "s", "v0", "u_max", "k_p", "k_d"):
        assert got[name] == pytest.approx(d[name], rel=1e-12)


def test_every_object_converts_itself_and_keeps_the_rest_length():
    units = Units(m_t=3.0, k_g=4400.0)
    imp = Impedance(0.2, 0.3, l0=7.5)
    si = imp.to_si(units)
    assert si["K_p"] == pytest.approx(0.2 * 4400.0)
    assert si["K_d"] == pytest.approx(0.3 * math.sqrt(3.0 * 4400.0))
    back = Impedance.from_si(si["K_p"], si["K_d"], units, si["rest_length"])
    assert (back.k_p, back.k_d, back.l0) == pytest.approx((0.2, 0.3, 7.5), rel=1e-14)
    robot, u2 = Robot.from_si(**{k: v for k, v in Robot(5, 20, 8.2, 4.0).to_si(units).items()
                                 if k not in ("U_max",)}, k_g=4400.0,
                              U_max=8.2 * units.force)
    assert (robot.r_m, robot.s, robot.u_max, robot.l0) == pytest.approx((5, 20, 8.2, 4.0))
    assert u2 == units


def _object_with(field, value):
    if field == "v0":
        return Impact(value)
    if field in ("k_p", "k_d"):
        return Impedance(**{"k_p": 0.1, "k_d": 0.1, field: value})
    return Robot(**{"r_m": 5.0, "s": 20.0, field: value})


@pytest.mark.parametrize("kwargs,name", [
    ({"v0": 0.5}, "v0"), ({"r_m": 0}, "r_m"), ({"s": -1}, "s"), ({"u_max": 0}, "u_max"),
    ({"k_p": -0.1}, "k_p"), ({"k_d": -1}, "k_d"), ({"v0": math.nan}, "v0"),
    ({"s": math.inf}, "s"), ({"l0": 25.0}, "l0"), ({"l0": -1.0}, "l0"),
])
def test_dimensionless_bad_input_names_parameter(kwargs, name):
    (field, value), = kwargs.items()
    with pytest.raises(ParameterError) as e:
        _object_with(field, value)
    assert e.value.parameter == name
    assert isinstance(e.value, ValueError)
    assert "np." not in str(e.value)  # plain numbers, no numpy repr


@pytest.mark.parametrize("field,value", [
    ("m_b", -1.0), ("m_f", 0.0), ("k_g", math.nan), ("stroke", 0.0), ("v0", 1.0),
    ("u_max", -3.0), ("K_p", -1.0), ("K_d", math.inf),
])
def test_physical_bad_input_names_parameter(field, value):
    kw = dict(m_b=2.5, m_f=0.5, k_g=4400.0, stroke=0.13, v0=-1.0, K_p=1.0, K_d=1.0)
    kw[field] = value
    with pytest.raises(ParameterError, match=field):
        PhysicalParams(**kw)


def _paper_literals(tree):
    """Code (not docstrings) that types the paper's robot: 8.2, or r_m=5 / s=20 as a keyword
    or a default."""
    import ast

    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and node.value == 8.2:
            yield node.lineno
        if isinstance(node, ast.keyword) and isinstance(node.value, ast.Constant):
            if (node.arg, node.value.value) in (("r_m", 5), ("s", 20)):
                yield node.lineno
        if isinstance(node, ast.arguments):
            pos = node.posonlyargs + node.args
            pairs = list(zip(pos[len(pos) - len(node.defaults):], node.defaults, strict=True))
            pairs += [(a, d) for a, d in zip(node.kwonlyargs, node.kw_defaults, strict=True)
                      if d is not None]
            for arg, default in pairs:
                if isinstance(default, ast.Constant) and (arg.arg, default.value) in (
                        ("r_m", 5), ("s", 20), ("u_max", 8.2)):
                    yield default.lineno


def test_the_paper_numbers_live_in_one_place():
    """The paper's r_m, s and u_max are typed once, in softlanding/model/robot.py."""
    import ast
    from pathlib import Path

    pkg = Path(__file__).resolve().parents[3] / "softlanding"
    hits = sorted({(f.relative_to(pkg).as_posix(), line) for f in pkg.rglob("*.py")
                   for line in _paper_literals(ast.parse(f.read_text()))})
    assert len(hits) == 1 and hits[0][0] == "model/robot.py", hits
