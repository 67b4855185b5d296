"""Tests of the beat metrics on arrays (beatsync.evaluate.beats)."""

import warnings

import numpy as np
import pytest

from beatsync.errors import BeatsyncWarning, ParameterError
from beatsync.evaluate import beats as ev
from beatsync.evaluate.beats import (
    METRICS,
    count_octave_errors,
    count_other_tempo,
    diagnose_times,
    evaluate,
    octave_relation,
    tempo_octave,
    validate,
)

REF = np.arange(0.5, 20.0, 0.5)


def test_perfect_estimate_scores_one():
    s = evaluate(REF, REF, min_beat_time=0.0)
    assert set(s) == set(METRICS)
    for k in METRICS:
        if k != "Information gain":
            assert s[k] == pytest.approx(1.0), k
    assert s["Information gain"] == pytest.approx(1.0)


def test_double_tempo_is_any_level_only():
    est = np.arange(0.5, 20.0, 0.25)
    s = evaluate(REF, est, min_beat_time=0.0)
    assert s["Correct Metric Level Total"] == 0.0
    assert s["Any Metric Level Total"] > 0.9
    assert s["F-measure"] == pytest.approx(2 / 3, abs=0.01)


def test_min_beat_time_is_applied():
    est = REF.copy()
    est[:4] += 0.2  # wrong only in the first 2 s
    assert evaluate(REF, est, min_beat_time=0.0)["F-measure"] < 1.0
    assert evaluate(REF, est, min_beat_time=2.3)["F-measure"] == pytest.approx(1.0)


def test_min_beat_time_required():
    with pytest.raises(TypeError):
        evaluate(REF, REF)  # type: ignore[call-arg]


def test_empty_estimate_warns_zero():
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        s = evaluate(REF, np.array([]), min_beat_time=0.0)
    assert all(v == 0.0 for v in s.values())
    assert any(issubclass(w.category, BeatsyncWarning) for w in rec)


@pytest.mark.parametrize(
    "ref, est, mbt",
    [
        (REF[::-1], REF, 0.0),  # not increasing
        (REF, np.r_[REF[:3], REF[2:]], 0.0),  # duplicate
        (REF * 1000, REF, 0.0),  # milliseconds
        (REF, np.r_[-0.1, REF], 0.0),  # negative time
        (REF, np.r_[REF, np.nan], 0.0),  # NaN
        (REF.reshape(-1, 1), REF, 0.0),  # 2-D
        (REF, REF, -1.0),  # negative min_beat_time
        (REF, REF, float("nan")),
        (REF, REF, "five"),
    ],
)
def test_bad_input_raises(ref, est, mbt):
    with pytest.raises(ParameterError):
        evaluate(ref, est, min_beat_time=mbt)


@pytest.mark.parametrize(
    "est, match",
    [
        (np.round(REF * 100), "looks like frame indices"),  # frames at 100 frames/s
        (np.round(REF * 86.13), "looks like frame indices"),  # librosa frames (hop 512)
        (REF * 1000, "looks like milliseconds"),
        (REF * 1000 + 0.25, "looks like milliseconds"),
        (REF * 100000, "looks like sample indices"),
        (np.round(REF * 22050), "looks like sample indices"),
        # frames at 10 frames/s: 5 apart at 120 BPM, once read as beats 5 s apart
        (np.round(REF * 10), "looks like frame indices"),
        (REF * 7.3, "looks like something slower than any beat"),
        (np.array([50000.0, 60000.0]), "milliseconds or frame indices"),
    ],
)
def test_validate_says_what_the_times_look_like(est, match):
    with pytest.raises(ParameterError, match=match):
        validate(REF, est)
    with pytest.raises(ParameterError, match="estimated beats"):
        evaluate(REF, est, min_beat_time=0.0)


def test_diagnose_accepts_seconds():
    assert diagnose_times(REF) is None
    assert diagnose_times(np.array([])) is None
    assert diagnose_times(np.arange(0.0, 600.0, 2.0)) is None  # 30 BPM, 10 minutes
    assert diagnose_times(np.array([1.0, 9.0])) is None


def test_tempo_octave_from_beats():
    out = tempo_octave(REF, np.arange(0.5, 20.0, 0.25))
    assert out["tempo_ref"] == pytest.approx(120.0)
    assert out["tempo_est"] == pytest.approx(240.0)
    assert out["octave"] == "double"
    assert np.isnan(tempo_octave(REF, np.array([1.0]))["tempo_est"])
    assert tempo_octave(REF, np.array([1.0]))["octave"] == "other"


def test_octave_counts():
    octaves = ["correct", "double", "half", "other", "third", "correct"]
    assert count_octave_errors(octaves) == 3
    assert count_other_tempo(octaves) == 1
    assert count_octave_errors([]) == 0


def test_evaluate_never_runs_a_tracker():
    import ast
    from pathlib import Path

    tree = ast.parse(Path(ev.__file__).read_text())
    imported = {
        (node.module or "") for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
    } | {a.name for node in ast.walk(tree) if isinstance(node, ast.Import) for a in node.names}
    assert not {
        m for m in imported if m.lstrip(".").split(".")[0] in ("beats", "other_trackers", "study")
    }


@pytest.mark.parametrize(
    "est, ref, name",
    [
        (120, 120, "correct"),
        (240, 120, "double"),
        (61, 120, "half"),
        (180, 60, "triple"),
        (40, 120, "third"),
        (100, 120, "other"),
        (float("nan"), 120, "other"),
    ],
)
def test_octave_relation(est, ref, name):
    assert octave_relation(est, ref) == name


def test_mir_eval_time_limit_is_mir_evals():
    """Copied so that reading annotations does not import mir_eval: it must stay its value."""
    import mir_eval.beat

    assert ev.MIR_EVAL_MAX_TIME == mir_eval.beat.MAX_TIME
