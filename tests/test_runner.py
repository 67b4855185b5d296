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


def _outputs(path):
    nb = nbformat.read(path, as_version=4)
    return "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs)


SPAN = (
    "import os, time\n"
    "t0 = time.time()\n"
    "time.sleep(n)\n"
    "print(t0, time.time(), os.environ.get('OPENBLAS_NUM_THREADS'))"
)


@pytest.mark.slow
def test_parallel_jobs_run_notebooks_side_by_side(tmp_path, monkeypatch):
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setattr("beatsync.runner.usable_cpus", lambda: 4)
    d = tmp_path / "notebooks"
    d.mkdir()
    for name in ("one", "two"):
        _notebook(d / f"{name}.ipynb", SPAN)
    p = tmp_path / "p.yaml"
    p.write_text("one: {n: 4}\ntwo: {n: 4}\n")
    out = tmp_path / "out"
    runs = run_notebooks(p, notebooks_dir=d, output_dir=out, jobs=2)
    assert [r.name for r in runs] == ["one", "two"]  # the parameter file's order
    spans = [_outputs(out / f"{name}.ipynb").split() for name in ("one", "two")]
    (a0, a1, threads), (b0, b1, _) = spans
    assert float(a0) < float(b1) and float(b0) < float(a1)  # they overlapped
    assert threads == "2"  # 4 CPUs shared by 2 notebooks
    manifest = json.loads((out / "run_manifest.json").read_text())
    assert [n["name"] for n in manifest["notebooks"]] == ["one", "two"]
    assert sorted(x.name for x in out.iterdir()) == ["one.ipynb", "run_manifest.json", "two.ipynb"]


@pytest.mark.slow
def test_parallel_failure_names_the_notebook_and_keeps_its_copy(tmp_path):
    from beatsync.runner import NotebookFailed

    d = tmp_path / "notebooks"
    d.mkdir()
    _notebook(d / "good.ipynb", "import time\ntime.sleep(30)")
    _notebook(d / "bad.ipynb", "raise RuntimeError('broken analysis')")
    p = tmp_path / "p.yaml"
    p.write_text("good: {}\nbad: {}\n")
    out = tmp_path / "out"
    with pytest.raises(NotebookFailed, match="(?s)'bad' failed.*RuntimeError: broken analysis"):
        run_notebooks(p, notebooks_dir=d, output_dir=out, jobs=2)
    # the sleeping notebook was stopped, not awaited; nothing but the failed copy is left
    assert sorted(x.name for x in out.iterdir()) == ["bad.failed.ipynb"]


@pytest.mark.parametrize("jobs", [0, -1, 1.5, True])
def test_jobs_must_be_a_whole_number(nbdir, tmp_path, jobs):
    p = tmp_path / "p.yaml"
    p.write_text("tiny: {}\n")
    with pytest.raises(ParameterError, match=f"jobs={jobs!r}"):
        run_notebooks(p, notebooks_dir=nbdir, output_dir=tmp_path / "out", jobs=jobs)
    assert not (tmp_path / "out").exists()


def test_cli_refuses_zero_jobs(nbdir, tmp_path, capsys):
    p = tmp_path / "p.yaml"
    p.write_text("tiny: {}\n")
    code = main(["reproduce", "--params", str(p), "--notebooks", str(nbdir), "--jobs", "0"])
    assert code == 3 and "--jobs 0" in capsys.readouterr().err
