"""Names of :data:`stereovar.__all__` for type checkers and editors.

``stereovar/__init__.py`` imports each on first access (``__getattr__``); this stub declares
where each comes from. ``tests/test_api.py`` checks that it lists exactly ``__all__`` and
that each import here is the one ``__getattr__`` makes. The deprecated Mitsuba aliases are
left out: import them from :mod:`stereovar.renderers.mitsuba`.
"""

from .estimators import ESTIMATORS as ESTIMATORS
from .estimators import get_estimator as get_estimator
from .estimators.seeds import StreamingVariance as StreamingVariance
from .estimators.seeds import variance_dataset as variance_dataset
from .estimators.seeds import variance_field as variance_field
from .estimators.seeds import variance_from_stores as variance_from_stores
from .figures.margins import margin_distribution_figure as margin_distribution_figure
from .figures.material_scatter import material_scatter_figure as material_scatter_figure
from .figures.rho_vs_spp import rho_vs_spp_figure as rho_vs_spp_figure
from .figures.teaser import teaser_figure as teaser_figure
from .ground_truth import MATERIAL_CLASSES as MATERIAL_CLASSES
from .ground_truth import compute_ground_truth as compute_ground_truth
from .ground_truth import summarize_ground_truth as summarize_ground_truth
from .intervention.metrics import intervention_metrics as intervention_metrics
from .intervention.scan import scan_cost_volume as scan_cost_volume
from .intervention.scan import scan_hit_rate as scan_hit_rate
from .intervention.scan import wta_disparity as wta_disparity
from .intervention.shuffle import apply_block_permutation as apply_block_permutation
from .intervention.shuffle import block_permutation as block_permutation
from .io.renders import RenderStore as RenderStore
from .io.store import open_dataset as open_dataset
from .io.store import write_dataset as write_dataset
from .renderers import RENDERERS as RENDERERS
from .renderers import get_renderer as get_renderer
from .rig import StereoRig as StereoRig
from .rig import make_rig as make_rig
from .scenes.generate import generate_scene as generate_scene
from .scenes.spec import load_scene_spec as load_scene_spec
from .seeding import SEED_POLICIES as SEED_POLICIES
from .seeding import derive_seed as derive_seed
from .seeding import render_seed as render_seed
from .statistics.correlation import pearson_over_mask as pearson_over_mask
from .statistics.regions import REGIONS as REGIONS
from .statistics.regions import region_masks as region_masks
from .statistics.regions import valid_set as valid_set
from .statistics.registry import METHODS as METHODS
from .statistics.registry import register_method as register_method
from .statistics.rows import correlation_rows as correlation_rows
from .statistics.summary import cross_scene_table as cross_scene_table
from .statistics.summary import intervention_table as intervention_table
from .statistics.summary import spp_sweep_table as spp_sweep_table
from .statistics.warp import align_variance as align_variance
from .statistics.warp import warp_right_to_left as warp_right_to_left

__version__: str

__all__ = [
    "__version__",
    "ESTIMATORS",
    "MATERIAL_CLASSES",
    "METHODS",
    "REGIONS",
    "RENDERERS",
    "RenderStore",
    "SEED_POLICIES",
    "StereoRig",
    "StreamingVariance",
    "align_variance",
    "apply_block_permutation",
    "block_permutation",
    "compute_ground_truth",
    "correlation_rows",
    "cross_scene_table",
    "derive_seed",
    "generate_scene",
    "get_estimator",
    "get_renderer",
    "intervention_metrics",
    "intervention_table",
    "load_scene_spec",
    "make_rig",
    "margin_distribution_figure",
    "material_scatter_figure",
    "open_dataset",
    "pearson_over_mask",
    "region_masks",
    "register_method",
    "render_seed",
    "rho_vs_spp_figure",
    "scan_cost_volume",
    "scan_hit_rate",
    "spp_sweep_table",
    "summarize_ground_truth",
    "teaser_figure",
    "valid_set",
    "variance_dataset",
    "variance_field",
    "variance_from_stores",
    "warp_right_to_left",
    "write_dataset",
    "wta_disparity",
]
