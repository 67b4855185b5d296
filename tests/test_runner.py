"""The notebook runner: parameter checks (papermill itself only warns)."""

import json
import os
from pathlib import Path

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
    with pytest.raises(ParameterError, match=r"\['m'\]"):
        check_params({"tiny": {"m": 1}}, nbdir)


def test_missing_and_unlisted_notebooks(nbdir):
    with pytest.raises(ParameterError, match="other"):
        check_params({"tiny": {}, "other": {}}, nbdir)
    with pytest.raises(ParameterError, match="tiny"):
        check_params({}, nbdir)


def test_bad_params_file(tmp_path):
    p = tmp_path / "p.yaml"
    p.write_text("- a\n- b\n")
    with pytest.raises(ParameterError, match="p.yaml"):
        load_params(p)
    with pytest.raises(ParameterError, match="none.yaml"):
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
    # the executed notebook names its source relative to the repository, not this machine
    assert nb.metadata["papermill"]["input_path"] == "notebooks/tiny.ipynb"
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
    assert threads == "1"  # one BLAS thread per kernel: sums independent of the cores
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
    with pytest.raises(NotebookFailed, match="(?s)'bad'.*broken analysis"):
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


@pytest.mark.parametrize("preset", [None, "3"])
def test_kernels_get_one_blas_thread_unless_the_user_chose(tmp_path, monkeypatch, preset):

    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        monkeypatch.delenv(var, raising=False)
    if preset:
        monkeypatch.setenv("OPENBLAS_NUM_THREADS", preset)
    d = tmp_path / "notebooks"
    d.mkdir()
    _notebook(d / "one.ipynb", SPAN)
    p = tmp_path / "p.yaml"
    p.write_text("one: {n: 0}\n")
    run_notebooks(p, notebooks_dir=d, output_dir=tmp_path / "out", jobs=1)
    assert _outputs(tmp_path / "out" / "one.ipynb").split()[2] == (preset or "1")


def test_a_run_of_some_notebooks_keeps_the_others_in_the_manifest(nbdir, tmp_path):
    # reproduce --only X: the manifest still describes every notebook in the folder
    _notebook(nbdir / "other.ipynb")
    full, ci = tmp_path / "full.yaml", tmp_path / "ci.yaml"
    full.write_text("other:\n  n: 5\ntiny:\n  n: 21\n")
    ci.write_text("other:\n  n: 1\ntiny:\n  n: 2\n")
    out = tmp_path / "out"
    run_notebooks(full, notebooks_dir=nbdir, output_dir=out, jobs=1)
    first = json.loads((out / "run_manifest.json").read_text())["notebooks"]
    run_notebooks(ci, notebooks_dir=nbdir, output_dir=out, only=["tiny"], jobs=1)
    manifest = json.loads((out / "run_manifest.json").read_text())
    entries = {n["name"]: n for n in manifest["notebooks"]}
    assert [n["name"] for n in manifest["notebooks"]] == ["other", "tiny"]
    assert entries["other"] == first[0]  # not run: as the full run recorded it
    assert entries["other"]["params_file"] == str(full)
    assert entries["tiny"]["parameters"] == {"n": 2}
    assert entries["tiny"]["params_file"] == manifest["params_file"] == str(ci)
    # a notebook whose executed copy is gone is not described
    (out / "other.ipynb").unlink()
    run_notebooks(ci, notebooks_dir=nbdir, output_dir=out, only=["tiny"], jobs=1)
    manifest = json.loads((out / "run_manifest.json").read_text())
    assert [n["name"] for n in manifest["notebooks"]] == ["tiny"]


@pytest.mark.skipif(os.name != "posix", reason="Unix sockets only where the system has them")
def test_kernels_talk_over_private_unix_sockets(tmp_path, capfd):
    # over TCP every kernel warned on stderr that it runs without encryption
    d = tmp_path / "notebooks"
    d.mkdir()
    body = (
        "from ipykernel.kernelapp import IPKernelApp\n"
        "app = IPKernelApp.instance()\n"
        "print(app.transport, app.ip)"
    )
    _notebook(d / "where.ipynb", body)
    p = tmp_path / "p.yaml"
    p.write_text("where: {}\n")
    run_notebooks(p, notebooks_dir=d, output_dir=tmp_path / "out", jobs=1)
    transport, ip = _outputs(tmp_path / "out" / "where.ipynb").split()
    assert transport == "ipc"
    folder = Path(ip).parent
    assert folder.name.startswith("beatsync-kernel-") and not folder.exists()  # removed
    assert "without encryption" not in capfd.readouterr().err


def test_a_temporary_folder_too_long_for_a_socket_path_falls_back_to_tcp(tmp_path, monkeypatch):

    long_tmp = tmp_path / ("t" * 100)
    long_tmp.mkdir()
    monkeypatch.setenv("TMPDIR", str(long_tmp))  # the notebook's worker process
    d = tmp_path / "notebooks"
    d.mkdir()
    body = "from ipykernel.kernelapp import IPKernelApp\nprint(IPKernelApp.instance().transport)"
    _notebook(d / "where.ipynb", body)
    p = tmp_path / "p.yaml"
    p.write_text("where: {}\n")
    run_notebooks(p, notebooks_dir=d, output_dir=tmp_path / "out", jobs=1)
    assert _outputs(tmp_path / "out" / "where.ipynb").split() == ["tcp"]
    assert list(long_tmp.iterdir()) == []  # its socket folder removed


def test_an_interrupt_after_the_run_leaves_no_running_copy(nbdir, tmp_path, monkeypatch):
    # Ctrl-C or SIGTERM (a KeyboardInterrupt in the worker) after papermill returned,
    # while the executed copy is read back: the hidden running copy was left behind
    import nbformat as nbf

    from beatsync import runner

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(nbf, "read", interrupted)
    dest = tmp_path / "out" / "tiny.ipynb"
    dest.parent.mkdir()
    spec = {"parameters": {"n": 1}, "dest": str(dest), "write_to": str(dest)}
    with pytest.raises(KeyboardInterrupt):
        runner._execute("tiny", str(nbdir / "tiny.ipynb"), **spec)
    assert list(dest.parent.iterdir()) == []


def test_a_failing_notebook_is_named_and_kept_for_its_traceback(tmp_path):
    from beatsync.runner import NotebookFailed

    d = tmp_path / "notebooks"
    d.mkdir()
    _notebook(d / "bad.ipynb", "raise RuntimeError('broken analysis')")
    p = tmp_path / "p.yaml"
    p.write_text("bad: {}\n")
    out = tmp_path / "out"
    with pytest.raises(NotebookFailed, match="(?s)'bad'.*broken analysis"):
        run_notebooks(p, notebooks_dir=d, output_dir=out, jobs=1)
    assert sorted(x.name for x in out.iterdir()) == ["bad.failed.ipynb"]


def test_cli_check_in_place_and_quiet(nbdir, tmp_path, capsys):
    p = tmp_path / "p.yaml"
    p.write_text("tiny:\n  n: 21\n")
    base = ["reproduce", "--params", str(p), "--notebooks", str(nbdir)]
    assert main([*base, "--check"]) == 0
    assert "OK for 1 notebook(s): tiny" in capsys.readouterr().out
    assert sorted(x.name for x in nbdir.iterdir()) == ["tiny.ipynb"]  # nothing run
    # --quiet: nothing but errors and warnings, on either stream
    assert main([*base, "--in-place", "--quiet"]) == 0
    assert capsys.readouterr() == ("", "")
    assert "42\n" in _outputs(nbdir / "tiny.ipynb")  # the notebook itself, executed
    assert sorted(x.name for x in nbdir.iterdir()) == ["tiny.ipynb"]  # and no manifest


def test_a_relative_results_folder_is_found_from_the_notebooks_whatever_the_cwd(
    tmp_path, monkeypatch
):
    # papermill notebooks/X.ipynb from the repository root wrote "../results" outside it
    from beatsync.study.artifacts import results_folder

    root = Path(__file__).resolve().parents[1]
    for cwd in (root, root / "notebooks", root / "src" / "beatsync", tmp_path):
        monkeypatch.chdir(cwd)
        assert results_folder("../results/ci") == root / "results" / "ci", cwd
    assert results_folder(tmp_path / "r") == tmp_path / "r"  # absolute: as given
    # another clone found from the current folder, before the package's own
    other = tmp_path / "clone"
    (other / "notebooks").mkdir(parents=True)
    (other / "pyproject.toml").write_text("")
    monkeypatch.chdir(other / "notebooks")
    assert results_folder("../results") == other / "results"


def test_a_file_that_is_not_a_notebook_is_refused_by_name(nbdir):
    (nbdir / "broken.ipynb").write_text("{not json")
    with pytest.raises(ParameterError, match="broken.ipynb"):
        check_params({"tiny": {}, "broken": {}}, nbdir)
