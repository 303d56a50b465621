import math

import pytest

from softlanding import DimensionlessParams, ParameterError, PhysicalParams, paper_rig


def test_paper_rig_scales_to_paper_numbers():
    d = paper_rig().to_dimensionless()
    assert d.r_m == pytest.approx(5.0)
    assert d.s == pytest.approx(20.0)
    assert d.u_max == pytest.approx(8.2)
    # velocity scale sqrt(g^2 m_t / k_g): 1.2 m/s is v0 = -4.68 (the paper says -4.8)
    assert d.v0 == pytest.approx(-1.2 / math.sqrt(9.81**2 * 3.0 / 4400.0))


def test_round_trip_both_ways():
    ph = PhysicalParams(m_b=7.0, m_f=1.3, k_g=12_000.0, stroke=0.2, v0=-2.0, u_max=500.0,
                        K_p=3000.0, K_d=150.0)
    back = ph.to_dimensionless().to_physical(ph.m_t, ph.k_g, ph.g)
    for name in ("m_b", "m_f", "k_g", "stroke", "v0", "u_max", "K_p", "K_d"):
        assert getattr(back, name) == pytest.approx(getattr(ph, name), rel=1e-12)
    d = DimensionlessParams(r_m=3, s=12, v0=-4, u_max=6, k_p=0.3, k_d=0.2)
    again = d.to_physical(10.0, 5000.0).to_dimensionless()
    for name in ("r_m", "s", "v0", "u_max", "k_p", "k_d"):
        assert getattr(again, name) == pytest.approx(getattr(d, name), rel=1e-12)


@pytest.mark.parametrize("kwargs,name", [
    ({"v0": 0.5}, "v0"), ({"r_m": 0}, "r_m"), ({"s": -1}, "s"), ({"u_max": 0}, "u_max"),
    ({"k_p": -0.1}, "k_p"), ({"k_d": -1}, "k_d"), ({"v0": math.nan}, "v0"),
    ({"s": math.inf}, "s"),
])
def test_dimensionless_bad_input_names_parameter(kwargs, name):
    with pytest.raises(ParameterError) as e:
        DimensionlessParams(**kwargs)
    assert e.value.parameter == name
    assert isinstance(e.value, ValueError)


@pytest.mark.parametrize("field,value", [
    ("m_b", -1.0), ("m_f", 0.0), ("k_g", math.nan), ("stroke", 0.0), ("v0", 1.0),
    ("u_max", -3.0), ("K_p", -1.0), ("K_d", math.inf),
])
def test_physical_bad_input_names_parameter(field, value):
    kw = dict(m_b=2.5, m_f=0.5, k_g=4400.0, stroke=0.13, v0=-1.0)
    kw[field] = value
    with pytest.raises(ParameterError, match=field):
        PhysicalParams(**kw)
