//! The main job's figures: a [`Study`] summed up in the numbers its JSON line and its
//! report's table show.

use haunts_affordance::activity_at::RateCheck;
use haunts_planning::PathMetrics;
use haunts_tracking::eval::mot::ClearMot;
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use super::{AlignmentErrors, AlignmentStudy, SimulatedDay, Study};
use crate::pipeline::serve::activity_along;

/// The main job's figures ([`Study::summary`]). Serialised (serde), it is the JSON object
/// the `pipeline` example prints, with the keys listed below; path metrics as `{length,
/// activity_mean, activity_var, activity_max}`. Two keys hold lists: `per_layout`
/// (hypertime on each layout of [`HypertimeStudy::by_layout`](super::HypertimeStudy):
/// `{layout, test, hypertime_loglik, static_loglik, periods_s, period_validated}`) and
/// `plans_at_times` (each plan of [`Study::timed`]: `{hour, without_layer, with_layer,
/// activity_at_HH_MM_along_it}`, the hours after
/// [`HypertimeStudy::midnight`](super::HypertimeStudy::midnight), the last key the activity
/// at the last time along the plan with the layer: the main job's
/// `activity_at_12_30_along_it`, how much of the 12:30 activity the 08:00 plan meets).
///
/// The summary is read through its JSON (`serde_json::to_value(&summary)?["mota"]`); the
/// typed results behind each figure are the [`Study`]'s fields. Its keys:
/// - `days`: Days studied.
/// - `layouts_true`: Distinct true layouts among them.
/// - `layouts_found`: Layouts of the library.
/// - `layout_pairwise_accuracy`: The library's pairwise (Rand) accuracy against the true layouts.
/// - `layout_ari`: The library's adjusted Rand index.
/// - `layout_pairwise_accuracy_paper`: Seed 000's greedy clustering's pairwise accuracy.
/// - `layout_ari_paper`: Seed 000's greedy clustering's adjusted Rand index.
/// - `layout_pairwise_accuracy_complete_linkage`: Complete linkage's pairwise accuracy.
/// - `affordance_own_tables`: `"k/n"`: k of the n layouts [`Study::own_tables`] scored are denser
///   at their own tables and sofas than at the other layouts'.
/// - `mota`: CLEAR MOT's accuracy pooled over the days ([`ClearMot::pooled`]: one minus the misses,
///   false positives and identity switches of all days over all their visible people).
/// - `motp`: CLEAR MOT's precision pooled over the days: the mean distance of all matches, metres.
/// - `odometry_rms`: The days' mean RMS position error of the odometry, metres.
/// - `corrected_rms`: The days' mean RMS position error of the corrected poses, metres.
/// - `hypertime_loglik`: Hypertime's mean log-likelihood per test point (the model of all days;
///   `None` without a test point).
/// - `static_loglik`: Its static baseline's.
/// - `train`: Training points (thinned).
/// - `test`: Test points.
/// - `by_layout_hypertime_loglik`: The per-layout hypertime models' log-likelihood per test point,
///   pooled over their layouts (0 without any).
/// - `by_layout_static_loglik`: Their static baselines', pooled the same way.
/// - `by_layout_test`: The test points of those layouts.
/// - `ta_trajectories`: Tracks kept by the dummy filter for the TA map.
/// - `activity_threshold`: θ of the activity-aware A*
///   ([`PlanStudy::threshold`](super::PlanStudy)).
/// - `plain`: Plain A* across the busiest layout, against the TA map.
/// - `activity_aware`: Seed 002's activity-aware A*, against the TA map.
/// - `affordance_layer_without`: A* without the busiest layout's affordance layer, against its
///   affordance.
/// - `affordance_layer_with`: A* with it.
/// - `rhythm_periods_s`: The periods of the hypertime model that gave the daily rhythm of the timed
///   plans.
/// - `rate_rhythm`: The check of the rate's rhythm on held-out training days, as `{days, rmse,
///   flat_rmse, mean_count, validated}` ([`RateCheck`]'s `rhythm_rmse` and `accepted`).
/// - `alignment_error`: for days from random start poses ([`Study::alignment`]), the
///   registrations' errors against the simulator's truth, `{median_m, max_m, median_deg,
///   max_deg}` ([`AlignmentErrors`]); absent otherwise (and when no day was registered).
/// - `refused_days`: for days from random start poses, the days whose registration was
///   refused and which were left out (`days` counts the others); absent otherwise.
/// - `out`: The output folder ([`Study::write`] sets it; empty otherwise).
/// - `seconds`: Wall time of the run up to its report, seconds ([`Study::write`] sets it; 0
///   otherwise).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    pub(crate) days: usize,
    pub(crate) layouts_true: usize,
    pub(crate) layouts_found: usize,
    pub(crate) layout_pairwise_accuracy: f64,
    pub(crate) layout_ari: f64,
    pub(crate) layout_pairwise_accuracy_paper: f64,
    pub(crate) layout_ari_paper: f64,
    pub(crate) layout_pairwise_accuracy_complete_linkage: f64,
    pub(crate) affordance_own_tables: String,
    pub(crate) mota: f64,
    pub(crate) motp: f64,
    pub(crate) odometry_rms: f64,
    pub(crate) corrected_rms: f64,
    pub(crate) hypertime_loglik: Option<f64>,
    pub(crate) static_loglik: Option<f64>,
    pub(crate) train: usize,
    pub(crate) test: usize,
    pub(crate) by_layout_hypertime_loglik: f64,
    pub(crate) by_layout_static_loglik: f64,
    pub(crate) by_layout_test: usize,
    per_layout: Vec<LayoutHypertime>,
    pub(crate) ta_trajectories: usize,
    pub(crate) activity_threshold: f64,
    #[serde(serialize_with = "metrics")]
    pub(crate) plain: PathMetrics,
    #[serde(serialize_with = "metrics")]
    pub(crate) activity_aware: PathMetrics,
    #[serde(serialize_with = "metrics")]
    pub(crate) affordance_layer_without: PathMetrics,
    #[serde(serialize_with = "metrics")]
    pub(crate) affordance_layer_with: PathMetrics,
    pub(crate) rhythm_periods_s: Vec<f64>,
    #[serde(serialize_with = "rate_check")]
    pub(crate) rate_rhythm: Option<RateCheck>,
    plans_at_times: Vec<PlanAtTime>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) alignment_error: Option<AlignmentErrors>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) refused_days: Option<usize>,
    pub(crate) out: String,
    pub(crate) seconds: f64,
}

/// Hypertime on one layout of the library, in a [`Summary`]'s JSON.
#[derive(Debug, Clone, PartialEq, Serialize)]
struct LayoutHypertime {
    layout: usize,
    test: usize,
    hypertime_loglik: Option<f64>,
    static_loglik: Option<f64>,
    periods_s: Vec<f64>,
    period_validated: bool,
}

/// The trip planned at one time of day, in a [`Summary`]'s JSON.
#[derive(Debug, Clone, PartialEq)]
struct PlanAtTime {
    /// Hours after [`HypertimeStudy::midnight`](super::HypertimeStudy::midnight).
    hour: f64,
    without_layer: PathMetrics,
    with_layer: PathMetrics,
    /// The last time's activity along the path planned with the layer.
    activity_at_last: f64,
    /// The hour of the last time (as `hour`), which names `activity_at_last`'s key.
    last_hour: f64,
}

impl Serialize for PlanAtTime {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(4))?;
        map.serialize_entry("hour", &self.hour)?;
        map.serialize_entry("without_layer", &MetricsJson::from(&self.without_layer))?;
        map.serialize_entry("with_layer", &MetricsJson::from(&self.with_layer))?;
        let key = format!("activity_at_{}_along_it", clock(self.last_hour, '_'));
        map.serialize_entry(&key, &self.activity_at_last)?;
        map.end()
    }
}

impl Summary {
    /// The hour (after midnight) of each plan of [`Study::timed`] (for the figures' labels).
    #[cfg(feature = "figures")]
    pub(crate) fn plan_hours(&self) -> impl Iterator<Item = f64> + '_ {
        self.plans_at_times.iter().map(|p| p.hour)
    }
}

/// `hour` (hours after midnight) as `HH{separator}MM`.
pub(crate) fn clock(hour: f64, separator: char) -> String {
    let minutes = (hour * 60.0).round() as i64;
    format!(
        "{:02}{separator}{:02}",
        minutes.div_euclid(60),
        minutes.rem_euclid(60)
    )
}

/// Path metrics as the summary's JSON names them.
#[derive(Serialize)]
struct MetricsJson {
    length: f64,
    activity_mean: f64,
    activity_var: f64,
    activity_max: f64,
}

impl From<&PathMetrics> for MetricsJson {
    fn from(m: &PathMetrics) -> Self {
        Self {
            length: m.length,
            activity_mean: m.activity_mean,
            activity_var: m.activity_variance,
            activity_max: m.activity_max,
        }
    }
}

fn metrics<S: Serializer>(m: &PathMetrics, s: S) -> Result<S::Ok, S::Error> {
    MetricsJson::from(m).serialize(s)
}

#[allow(clippy::ref_option)] // serde's `serialize_with` signature
fn rate_check<S: Serializer>(check: &Option<RateCheck>, s: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct Rate {
        days: usize,
        rmse: f64,
        flat_rmse: f64,
        mean_count: f64,
        validated: bool,
    }
    check
        .map(|c| Rate {
            days: c.days,
            rmse: c.rhythm_rmse,
            flat_rmse: c.flat_rmse,
            mean_count: c.mean_count,
            validated: c.accepted,
        })
        .serialize(s)
}

impl Study {
    /// The study's figures; `out` and `seconds` are left empty ([`Study::write`] sets them).
    ///
    /// Means over days divide by the number of days (NaN without a day).
    pub fn summary(&self) -> Summary {
        let (days, layouts, hyper, plans) =
            (&self.days, &self.layouts, &self.hypertime, &self.plans);
        let mot = ClearMot::pooled(days.iter().map(|d| d.score.mot));
        let mean =
            |f: fn(&SimulatedDay) -> f64| days.iter().map(f).sum::<f64>() / days.len() as f64;
        let (by_h, by_s, by_n) = hyper
            .by_layout
            .iter()
            .fold((0.0, 0.0, 0), |(h, s, n), (_, l)| {
                (
                    h + l.hypertime_ll.sum,
                    s + l.static_ll.sum,
                    n + l.hypertime_ll.used,
                )
            });
        let per_test = |sum: f64| sum / by_n.max(1) as f64;
        let last = self.timed.plans.last();
        let hour = |time: f64| (time - hyper.midnight()) / 3600.0;
        let denser = self.own_tables.iter().filter(|o| o.own > o.other).count();
        Summary {
            days: days.len(),
            layouts_true: layouts.true_layouts(),
            layouts_found: layouts.library.layouts().len(),
            layout_pairwise_accuracy: layouts.ours.rand_index,
            layout_ari: layouts.ours.adjusted_rand_index,
            layout_pairwise_accuracy_paper: layouts.paper.rand_index,
            layout_ari_paper: layouts.paper.adjusted_rand_index,
            layout_pairwise_accuracy_complete_linkage: layouts.linkage.rand_index,
            affordance_own_tables: format!("{denser}/{}", self.own_tables.len()),
            mota: mot.mota,
            motp: mot.motp,
            odometry_rms: mean(|d| d.score.pose_errors.odometry_rms),
            corrected_rms: mean(|d| d.score.pose_errors.corrected_rms),
            hypertime_loglik: hyper.all.hypertime_ll.mean(),
            static_loglik: hyper.all.static_ll.mean(),
            train: hyper.train.len(),
            test: hyper.test.len(),
            by_layout_hypertime_loglik: per_test(by_h),
            by_layout_static_loglik: per_test(by_s),
            by_layout_test: by_n,
            per_layout: hyper
                .by_layout
                .iter()
                .map(|(id, l)| LayoutHypertime {
                    layout: *id,
                    test: l.hypertime_ll.used,
                    hypertime_loglik: l.hypertime_ll.mean(),
                    static_loglik: l.static_ll.mean(),
                    periods_s: l.hypertime.periods().to_vec(),
                    period_validated: !l.hypertime.report().selection.no_period_validated(),
                })
                .collect(),
            ta_trajectories: self.ta.kept,
            activity_threshold: plans.threshold,
            plain: plans.plain.metrics,
            activity_aware: plans.aware.metrics,
            affordance_layer_without: plans.layer.without_layer,
            affordance_layer_with: plans.layer.with_layer,
            rhythm_periods_s: self.timed.periods.clone(),
            rate_rhythm: self.timed.rate_check,
            plans_at_times: self
                .timed
                .plans
                .iter()
                .map(|p| PlanAtTime {
                    hour: hour(p.time),
                    without_layer: p.plans.without_layer,
                    with_layer: p.plans.with_layer,
                    activity_at_last: last.map_or(f64::NAN, |l| {
                        activity_along(&p.plans.with_path, &l.served.density).0
                    }),
                    last_hour: last.map_or(f64::NAN, |l| hour(l.time)),
                })
                .collect(),
            alignment_error: self.alignment.as_ref().and_then(AlignmentStudy::errors),
            refused_days: self.alignment.as_ref().map(|a| a.refused.len()),
            out: String::new(),
            seconds: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn metrics(length: f64) -> PathMetrics {
        PathMetrics {
            length,
            activity_mean: 0.5,
            activity_variance: 0.25,
            activity_max: 2.0,
        }
    }

    #[test]
    fn a_plan_at_a_time_is_keyed_by_the_last_time_and_its_metrics_by_the_summary_names() {
        let plan = PlanAtTime {
            hour: 8.0,
            without_layer: metrics(10.0),
            with_layer: metrics(11.0),
            activity_at_last: 0.125,
            last_hour: 12.5,
        };
        let json = serde_json::to_value(&plan).unwrap();
        assert_eq!(
            json,
            serde_json::json!({
                "hour": 8.0,
                "without_layer": {"length": 10.0, "activity_mean": 0.5, "activity_var": 0.25, "activity_max": 2.0},
                "with_layer": {"length": 11.0, "activity_mean": 0.5, "activity_var": 0.25, "activity_max": 2.0},
                "activity_at_12_30_along_it": 0.125,
            })
        );
    }

    #[test]
    fn clock_rounds_to_the_minute_and_pads() {
        assert_eq!(clock(8.0, ':'), "08:00");
        assert_eq!(clock(12.5, '_'), "12_30");
        assert_eq!(clock(9.0 + 59.7 / 60.0, ':'), "10:00");
        assert_eq!(clock(0.25, ':'), "00:15");
    }
}
