"""Music-driven dance composition over weighted motion graphs (paper B).

Xu, Takagi, Kawada, "Automatic composition of motion capture animation for music
synchronization". A motion library becomes a :class:`WeightedMotionGraph` whose
nodes are beat frames (:mod:`beatsync.graph.build`); a dynamic programme over the
music's beat intervals chooses the path whose motion intensity follows the music's
(:mod:`beatsync.graph.search`: the DP, the multi-stage baseline and the random walk);
the chosen intervals are time-warped onto the music beats and blended at transitions
(:mod:`beatsync.graph.warp`); :mod:`beatsync.graph.compose` is the public entry that
runs the whole chain, and :mod:`beatsync.graph.cache` keeps built graphs on disk.

Outside this stage: quality proxies are metrics in
:mod:`beatsync.evaluate.composition`, synthetic dances live in
:mod:`beatsync.synth.library`, and the paper-B notebooks call
:mod:`beatsync.study.paper_b`.

Data contract: event times in seconds (1-D float64, strictly increasing); motions
are :class:`beatsync.motion.Motion` with one skeleton structure per library.

Notebooks: ``notebooks/paper_b_tab01_search_speed.ipynb`` (paper B Table 1) and
``notebooks/paper_b_tab02_quality_proxies.ipynb`` (proxies for paper B Table 2).
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
    search,
)
from .warp import SynthesisResult, beat_warp, synthesize

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
    "search",
    "SearchResult",
    "conventional_search",
    "dp_search",
    "path_cost",
    "random_walk",
    "SynthesisResult",
    "beat_warp",
    "synthesize",
]
