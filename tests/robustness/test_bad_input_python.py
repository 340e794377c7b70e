"""The bad-input sweep on the Python package: None where a Brdf is expected, random numbers outside
[0, 1), bare words in specs, messages from hostile bytes."""
import numpy as np
import pytest

from conftest import import_brdfz


@pytest.fixture(scope="module")
def brdfz():
    return import_brdfz()


@pytest.fixture(scope="module")
def m(brdfz, tmp_path_factory):
    """A small table of a Lambertian model."""
    path = tmp_path_factory.mktemp("lambert") / "lambert.json"
    path.write_text('{"format": "brdfz-analytic", "version": 1, "model": "lambert", "parameters": '
                    '{"lambert.rho_r": 0.3, "lambert.rho_g": 0.4, "lambert.rho_b": 0.5}}')
    return brdfz.tabulate(brdfz.load(path), (8, 8, 16))


@pytest.mark.parametrize("call", [
    lambda b, m, p: b.tabulate(None),
    lambda b, m, p: b.compress(None, "tabular:res=8x8x16"),
    lambda b, m, p: b.compress(None, auto=True, max_error=0.1),
    lambda b, m, p: b.trial(None, "tabular:res=8x8x16"),
    lambda b, m, p: b.metrics(m, None),
    lambda b, m, p: b.metrics(None, m),
    lambda b, m, p: b.albedo(None, [0.1]),
    lambda b, m, p: b.save(None, p / "x.binary"),
    lambda b, m, p: b.fit(None, "lambert"),
    lambda b, m, p: b.metric_samples(None),
    lambda b, m, p: b.validate(None),
])
def test_none_for_a_brdf_is_a_type_error(brdfz, m, tmp_path, call):
    with pytest.raises(TypeError):
        call(brdfz, m, tmp_path)
    assert not (tmp_path / "x.binary").exists()


@pytest.mark.parametrize("bad", [-1e-9, 1.0, 1.5, np.nan, np.inf, -np.inf])
def test_sample_u_outside_unit_interval_is_a_value_error(m, bad):
    wo = np.array([[0.0, 0.3, 0.95]] * 4)
    u = np.full((4, 2), 0.5)
    u[2, 1] = bad
    with pytest.raises(ValueError, match=r"u\[2\]: .* is outside \[0, 1\)"):
        m.sample(wo, u)
    u[2, 1] = 0.0
    wi, pdf, _ = m.sample(wo, u)
    assert wi.shape == (4, 3) and np.all(pdf > 0)


@pytest.mark.parametrize("spec", ["tabular:wibble", "svd:foo", "tabular:res"])
def test_bare_word_in_a_spec_is_a_value_error(brdfz, m, spec):
    kind, word = spec.split(":")
    message = (rf"^{kind}: option {word} needs a value \({word}=\.\.\.\)$" if word == "res"
               else rf"^{kind}: unknown option\(s\) {word}$")
    with pytest.raises(ValueError, match=message):
        brdfz.compress(m, spec)
    with pytest.raises(ValueError, match=message):
        brdfz.trial(m, spec)


def test_misspelt_candidate_is_a_value_error(brdfz, m):
    with pytest.raises(ValueError, match=r"tabular: unknown option\(s\) rse"):
        brdfz.compress(m, auto=True, max_error=0.5, candidates=["tabular:rse=4x4x8"])


def test_metrics_of_a_brdf_against_itself_is_zero(brdfz, m):
    r = brdfz.metrics(m, brdfz.tabulate(m, (8, 8, 16)))
    assert r.cos_rmse.mean == 0.0 and r.log_rmse.mean == 0.0 and r.cos_rmse_rel.mean == 0.0


def test_hostile_bytes_in_a_file_give_a_format_error_with_escaped_text(brdfz, tmp_path):
    """A field name that is not UTF-8 and holds terminal controls: FormatError, not UnicodeDecodeError."""
    name = b"\x1b[2J\xff\xfe"
    data = b"tensor_file\x00\x01\x00" + (1).to_bytes(4, "little") + len(name).to_bytes(2, "little") + name
    data += (1).to_bytes(2, "little") + bytes([99])
    path = tmp_path / "hostile.bsdf"
    path.write_bytes(data)
    with pytest.raises(brdfz.FormatError) as e:
        brdfz.load(path)
    assert "\\x1b[2J\\xff\\xfe" in str(e.value) and "\x1b" not in str(e.value)


def test_none_for_the_mitsuba_bridge_is_a_type_error(brdfz):
    mi = pytest.importorskip("mitsuba")
    import brdfz.mitsuba

    mi.set_variant("scalar_rgb")
    with pytest.raises(TypeError, match="expected a brdfz.Brdf"):
        brdfz.mitsuba.bsdf(None)
