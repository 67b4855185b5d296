import shutil

import pytest

from beatsync import datasets
from beatsync.errors import ParameterError


def test_all_bundled_files_verify():
    assert all(datasets.verify_all().values())


def test_checksums_match_readme():
    readme = (datasets.data_dir() / "README.md").read_text()
    for rel, digest in datasets.CHECKSUMS.items():
        assert f"{digest}  {rel}" in readme


def test_corrupted_copy_is_refused(tmp_path, monkeypatch):
    shutil.copytree(datasets.data_dir(), tmp_path / "data")
    target = tmp_path / "data" / "audio" / "madmom" / "sample.beats"
    target.write_text(target.read_text() + "9.9\n")
    monkeypatch.setenv("BEATSYNC_DATA", str(tmp_path / "data"))
    monkeypatch.setattr(datasets, "_verified", set())
    with pytest.raises(ParameterError, match=r"sample\.beats"):
        datasets.path("audio/madmom/sample.beats")


def test_unknown_names():
    with pytest.raises(ParameterError, match="'99_99'"):
        datasets.load_salsa("99_99")
    with pytest.raises(ParameterError, match=r"'motion/nope\.bvh'"):
        datasets.path("motion/nope.bvh")
