"""Music-driven dance composition over weighted motion graphs (paper B).

Xu, Takagi, Kawada, "Automatic composition of motion capture animation for music
synchronization". Modules:

- :mod:`~beatsync.graph.build`: a motion library becomes a :class:`WeightedMotionGraph`
  whose nodes are beat frames; :mod:`~beatsync.graph.distance`: the frame distance
  of eq. 1 (stable floor-aligned point-cloud distance).
- :mod:`~beatsync.graph.timescale`: tempo-matched composition (clip tempi, tempo
  sub-groups, beat multiplicity, the time-scale bound).
- :mod:`~beatsync.graph.search`: the DP over the music's beats (and the dispatcher);
  :mod:`~beatsync.graph.baselines`: the multi-stage search and the random walk;
  :mod:`~beatsync.graph.objective`: their shared objective, result and checks.
- :mod:`~beatsync.graph.synthesis`: the chosen intervals time-warped onto the music and
  blended at transitions.
- :mod:`~beatsync.graph.plausibility`: root and joint rotation speeds against the
  library's.
- :mod:`~beatsync.graph.compose`: the public entry that runs the whole chain;
  :mod:`~beatsync.graph.cache`: built graphs kept on disk.

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
