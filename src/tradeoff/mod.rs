//! The quality–speed trade-off of per-frame BVH construction (Karras & Aila 2013, Figure 1): for
//! each builder configuration, a frame costs build time + rays / ray throughput, so which builder
//! is best depends on how many rays a frame traces. `model` holds the arithmetic (effective
//! throughput, the exact crossovers between configurations), `pareto` the SAH-vs-build-time
//! front, `configs` the configurations compared, `measure` how one is measured on the GPU,
//! `chart` the PNG charts and `text_backend` their text (feature "app"). `treelet tradeoff` and the viewer's
//! trade-off window use them.

#[cfg(feature = "app")]
mod chart;
mod configs;
mod measure;
mod model;
mod pareto;
#[cfg(feature = "app")]
mod text_backend;

#[cfg(feature = "app")]
pub use chart::{pareto_chart, rays_label, throughput_chart, CHART_SIZE};
pub use configs::{configurations, ROUNDS, SPLIT_PERCENTS, TREELET_SIZES};
pub use measure::{measure, median_of_passes, MeasureSettings};
pub use model::{
    best_ranges, effective_mrays, log_space, BestRange, Measurement, CURVE_POINTS, RAYS_RANGE,
};
pub use pareto::pareto_front;
