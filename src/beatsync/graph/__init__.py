"""Music-driven dance composition over weighted motion graphs (paper B).

Xu, Takagi, Kawada, "Automatic composition of motion capture animation for music
synchronization". A motion library becomes a :class:`WeightedMotionGraph` whose nodes
are beat frames (:mod:`~beatsync.graph.build`, eq. 1 in
:mod:`~beatsync.graph.distance`); a song is planned by tempo
(:mod:`~beatsync.graph.timescale`), searched (:mod:`~beatsync.graph.search`, the DP;
:mod:`~beatsync.graph.baselines`; shared :mod:`~beatsync.graph.objective`),
synthesized (:mod:`~beatsync.graph.synthesis`) and checked for speed
(:mod:`~beatsync.graph.plausibility`); :mod:`~beatsync.graph.compose` runs the chain
and :mod:`~beatsync.graph.cache` keeps built graphs on disk. Quality proxies are in
:mod:`beatsync.evaluate.composition`, synthetic dances in
:mod:`beatsync.synth.library`, the study in :mod:`beatsync.study.paper_b`.

Event times are seconds (1-D float64, strictly increasing). Notebooks:
``notebooks/paper_b_tab01_search_speed.ipynb`` (paper B Table 1) and
``notebooks/paper_b_tab02_quality_proxies.ipynb`` (proxies for Table 2).
"""

from .build import (
    WEIGHT_RULES,
    WeightedMotionGraph,
    build_graph,
    check_library,
    check_th,
    transition_weight,
)
from .distance import aligned_distance_matrix, aligned_pair_distance
from .search import (
    METHODS,
    SearchResult,
    conventional_search,
    dp_search,
    path_cost,
    random_walk,
)
from .synthesis import SynthesisResult, beat_warp, synthesize

__all__ = [
    "WEIGHT_RULES",
    "WeightedMotionGraph",
    "aligned_distance_matrix",
    "aligned_pair_distance",
    "build_graph",
    "check_library",
    "check_th",
    "transition_weight",
    "METHODS",
    "SearchResult",
    "conventional_search",
    "dp_search",
    "path_cost",
    "random_walk",
    "SynthesisResult",
    "beat_warp",
    "synthesize",
]
