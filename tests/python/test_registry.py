"""The format and representation registries as users see them: `brdfz formats`, `brdfz representations`,
brdfz.formats() / brdfz.representations(), the errors that name what is registered, and
docs/repr-specs.md kept equal to the registry."""
import json
import re

import pytest
from conftest import REPO, import_brdfz, run

FORMATS = {"alta": ".dat", "brdfz": ".brdfz", "cornell": ".brdf", "exr": ".exr", "json": ".json", "merl": ".binary",
           "rgl": ".bsdf"}


def test_formats_lists_every_format(cli):
    listed = json.loads(run(cli, "formats", "--json").stdout)
    assert FORMATS.items() <= {f["name"]: f["extensions"][0] for f in listed}.items()
    assert all(f["description"] and f["extensions"] and (f["reads"] or f["writes"]) for f in listed)
    by_name = {f["name"]: f for f in listed}
    assert by_name["cornell"]["reads"] == "measurements" and not by_name["cornell"]["writes"]
    assert by_name["merl"]["reads"] == "brdf" and by_name["merl"]["writes"]
    text = run(cli, "formats").stdout
    for name, ext in FORMATS.items():
        assert re.search(rf"^{name} +{re.escape(ext)} ", text, re.M)


def test_unknown_extension_names_the_registered_ones(cli, demo_table, tmp_path):
    # An output names only the writable extensions; an input every readable one.
    proc = run(cli, "convert", demo_table, tmp_path / "x.xyz", check=False)
    assert proc.returncode == 1
    message = proc.stderr.strip()
    assert "unknown file extension '.xyz'" in message and ".exr" in message and ".binary" in message
    assert ".brdf," not in message and ".dat" not in message and "\n" not in message
    proc = run(cli, "convert", demo_table, tmp_path / "x.dat", check=False)
    assert proc.returncode == 1 and "writing alta files is not supported" in proc.stderr
    assert not (tmp_path / "x.dat").exists()
    proc = run(cli, "info", tmp_path / "missing.xyz", check=False)
    assert proc.returncode == 1 and ".dat" in proc.stderr and ".brdf" in proc.stderr


def test_contents_tell_the_format_of_an_unknown_extension(cli, demo_table, tmp_path):
    renamed = tmp_path / "table.data"
    renamed.write_bytes(demo_table.read_bytes())
    info = json.loads(run(cli, "info", renamed, "--json").stdout)
    assert info["format"] == "merl" and info["dims"] == [90, 90, 180]
    junk = tmp_path / "junk.data"
    junk.write_bytes(b"\x00" * 100)
    proc = run(cli, "info", junk, check=False)
    assert proc.returncode == 1 and "contents of no known format" in proc.stderr


def test_representations_match_the_docs(cli):
    table = run(cli, "representations", "--markdown").stdout
    docs = (REPO / "docs" / "repr-specs.md").read_text()
    block = re.search(r"<!-- brdfz representations --markdown -->\n(.*?)<!-- end -->", docs, re.S)
    assert block, "docs/repr-specs.md lost its generated table"
    assert block.group(1) == table, "docs/repr-specs.md: paste `brdfz representations --markdown` into it"
    kinds = json.loads(run(cli, "representations", "--json").stdout)
    assert {k["kind"] for k in kinds} == {"analytic", "bivariate", "nmf", "pca", "rgl_svd", "svd", "tabular"}
    for k in kinds:
        assert k["summary"] and all(key["name"] and key["help"] and key["default"] for key in k["keys"])
        assert f"| `{k['kind']}` |" in table


@pytest.mark.parametrize("spec,message", [
    ("tabular:wibble", "tabular: unknown option(s) wibble"),
    ("svd:foo", "svd: unknown option(s) foo"),
    ("tabular:res", "tabular: option res needs a value"),
])
def test_bare_words_are_errors(cli, demo_table, tmp_path, spec, message):
    proc = run(cli, "compress", demo_table, "-o", tmp_path / "x.brdfz", "--repr", spec, check=False)
    assert proc.returncode == 1 and message in proc.stderr
    assert not (tmp_path / "x.brdfz").exists()
    brdfz = import_brdfz()
    if brdfz:
        with pytest.raises(ValueError, match=re.escape(message)):
            brdfz.compress(brdfz.load(demo_table), spec)


def test_python_lists_what_the_command_lists(cli):
    brdfz = import_brdfz()
    if not brdfz:
        pytest.skip("the Python module is not built")
    assert brdfz.formats() == json.loads(run(cli, "formats", "--json").stdout)
    assert brdfz.representations() == json.loads(run(cli, "representations", "--json").stdout)
