"""Scores: beat tracking (:mod:`beatsync.evaluate.beats`, mir_eval) and dance-music
beat alignment (:mod:`beatsync.evaluate.alignment`)."""
