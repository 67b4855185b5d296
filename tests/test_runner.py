"""The notebook runner: parameter checks (papermill itself only warns)."""

import json

import nbformat
import pytest

from beatsync.cli import main
from beatsync.errors import ParameterError
from beatsync.runner import check_params, load_params, run_notebooks


def _notebook(path, body="print(n * 2)"):
    nb = nbformat.v4.new_notebook()
    params = nbformat.v4.new_code_cell("n: int = 3  # how many")
    params.metadata["tags"] = ["parameters"]
    nb.cells = [params, nbformat.v4.new_code_cell(body)]
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    nbformat.write(nb, path)


@pytest.fixture
def nbdir(tmp_path):
    d = tmp_path / "notebooks"
    d.mkdir()
    _notebook(d / "tiny.ipynb")
    return d


def test_unknown_parameter_refused(nbdir, tmp_path):
    with pytest.raises(ParameterError, match=r"does not declare parameter\(s\) \['m'\]"):
        check_params({"tiny": {"m": 1}}, nbdir)


def test_missing_and_unlisted_notebooks(nbdir):
    with pytest.raises(ParameterError, match="do not exist"):
        check_params({"tiny": {}, "other": {}}, nbdir)
    with pytest.raises(ParameterError, match="not listed"):
        check_params({}, nbdir)


def test_bad_params_file(tmp_path):
    p = tmp_path / "p.yaml"
    p.write_text("- a\n- b\n")
    with pytest.raises(ParameterError, match="must map"):
        load_params(p)
    with pytest.raises(ParameterError, match="does not exist"):
        load_params(tmp_path / "none.yaml")


def test_run_executes_with_parameters(nbdir, tmp_path):
    p = tmp_path / "p.yaml"
    p.write_text("tiny:\n  n: 21\n")
    out = tmp_path / "out"
    runs = run_notebooks(p, notebooks_dir=nbdir, output_dir=out)
    assert [r.name for r in runs] == ["tiny"]
    nb = nbformat.read(out / "tiny.ipynb", as_version=4)
    texts = [o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert "42\n" in texts
    manifest = json.loads((out / "run_manifest.json").read_text())
    assert manifest["notebooks"][0]["parameters"] == {"n": 21}


def test_cli_check_reports_unknown_parameter(nbdir, tmp_path, capsys):
    p = tmp_path / "p.yaml"
    p.write_text("tiny:\n  typo: 1\n")
    code = main(["reproduce", "--params", str(p), "--notebooks", str(nbdir), "--check"])
    assert code == 3
    assert "typo" in capsys.readouterr().err


def test_project_param_files_match_notebooks():
    """Every committed notebook is listed in both parameter files, with declared names."""
    for f in ("params/ci.yaml", "params/paper.yaml"):
        check_params(load_params(f), "notebooks")
