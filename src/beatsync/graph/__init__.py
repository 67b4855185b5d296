"""Music-driven dance composition over weighted motion graphs (paper B).

Xu, Takagi, Kawada, "Automatic composition of motion capture animation for music
synchronization". A library becomes a :class:`WeightedMotionGraph` of beat frames
(:mod:`.build`, :mod:`.distance`); a song is planned by tempo (:mod:`.timescale`),
searched (:mod:`.search`, :mod:`.baselines`, :mod:`.objective`), synthesized
(:mod:`.synthesis`) and checked for speed (:mod:`.plausibility`); :mod:`.compose` runs
the chain, :mod:`.cache` keeps built graphs. Times are seconds. Notebooks:
``notebooks/paper_b_tab01_search_speed.ipynb`` (Table 1) and
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
