//! Seed 001's warped hypertime: where people are at any time of day.
//!
//! Detections `(x, y, t)` are projected to the hypertime space
//! `(x, y, cos 2πt/T₁, sin 2πt/T₁, …)` ([`Projection`], seed 001 eq. 1; one day by default),
//! clustered with Gustafson–Kessel fuzzy clustering ([`GkParams`], eqs. 2–7), and the clusters
//! become a Gaussian mixture whose conditional on the time dimensions is a density of people
//! over the plane at any time `t` ([`HypertimeModel::at`], a [`DensityMap`](crate::DensityMap)).
//! Periods can be chosen from the data's spectrum (FreMEn, [`PeriodSearch`]) and the number
//! of clusters by held-out likelihood ([`ClusterSearch`]). The same model without periods is
//! the time-independent baseline ([`HypertimeParams::without_time`]);
//! [`grid_log_likelihood`] scores models on test detections over one common grid.

mod eval;
mod fit;
mod gk;
mod model;
mod params;
mod projection;
mod read;
mod select;

pub(crate) use select::Blocks;

pub use eval::{
    DENSITY_UNITS, Evaluation, EvaluationParams, GridLogLikelihood, VisitPart, VisitSplit,
    evaluate, evaluate_with_training, grid_log_likelihood,
};
pub use gk::{GkClustering, GkParams, GkRun, Regularisation, kmeans_plus_plus};
pub use model::{
    BackgroundDensity, Component, FitReport, HypertimeModel, HypertimeSnapshot, UniformDensity,
};
pub use params::{Background, HypertimeParams, Moments, Uniform};
pub use params::{
    Calibration, CalibrationReport, ClusterSearch, CycleValidation, GivenPeriods, HoldOut,
    PeriodSearch, PeriodStep, Selection,
};
pub use projection::{DAY, Projection, TimedPoint};
pub use read::{DetectionColumns, parse_detections, read_detections, time_units_note};
