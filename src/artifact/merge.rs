//! Day artifacts into a layout library, as `haunts merge` does it: in recording order, each
//! day brought into the library's frame first.

use std::cmp::Ordering;

use crate::affordance::{AffordanceError, LayoutId, LayoutLibrary, RegisterParams, Registration};

use super::{Aligned, DayArtifact};

/// The order days are merged in: by the stamp of their first scan, ties by label (so that a
/// merge gives the same library whatever order its days arrive in).
pub fn recording_order(a: &DayArtifact, b: &DayArtifact) -> Ordering {
    a.span
        .0
        .total_cmp(&b.span.0)
        .then_with(|| a.label.cmp(&b.label))
}

/// A day that joined the library.
#[derive(Debug, Clone, PartialEq)]
pub struct MergedDay {
    /// Its position in the days given to [`merge_days`].
    pub index: usize,
    /// Its label.
    pub label: String,
    /// The layout it joined or started.
    pub layout: LayoutId,
    /// Whether it started a new layout.
    pub created: bool,
    /// The transform that brought it into the library's frame (`None`: it was there).
    pub alignment: Option<Registration>,
    /// Its occupied cells that fell outside the library's grid.
    pub outside: usize,
}

/// A day that did not join the library, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct RefusedDay {
    /// Its position in the days given to [`merge_days`].
    pub index: usize,
    /// Its label.
    pub label: String,
    /// Why: not aligned (with the registration's refusal), or the library's error.
    pub reason: String,
}

/// What [`merge_days`] did with each day.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MergeReport {
    /// The days ingested, in the order they were.
    pub ingested: Vec<MergedDay>,
    /// `(position, label)` of the days already in the library (skipped).
    pub duplicates: Vec<(usize, String)>,
    /// The days refused; the library is as if they had not been given.
    pub refused: Vec<RefusedDay>,
}

/// Merges `days` into `library` in [`recording_order`]: each day is classified against the
/// layouts of the days before it. A day already in the library (by label) is skipped; the
/// first day of an empty library on its cells starts it as it is; a day aligned onto this
/// library's cells ([`DayArtifact::alignment`] set, same geometry) goes in as it is; any other
/// day, in its own frame, is registered onto the layouts and moved
/// ([`DayArtifact::align`] under `params`) and refused when the registration is not
/// trustworthy: no day is ever merged misaligned.
///
/// Nothing here fails as a whole: each day's failure is a [`RefusedDay`] naming it, and the
/// library is unchanged by a refused day.
pub fn merge_days(
    library: &mut LayoutLibrary,
    days: Vec<DayArtifact>,
    params: &RegisterParams,
) -> MergeReport {
    let mut days: Vec<(usize, DayArtifact)> = days.into_iter().enumerate().collect();
    days.sort_by(|a, b| recording_order(&a.1, &b.1));
    let mut report = MergeReport::default();
    for (index, day) in days {
        let label = day.label.clone();
        let refuse = |reason: String| RefusedDay {
            index,
            label: label.clone(),
            reason,
        };
        if library.find_day(&label).is_some() {
            report.duplicates.push((index, label));
            continue;
        }
        let on_cells = day.map.geometry() == library.geometry();
        let as_it_is = on_cells && (library.layouts().is_empty() || day.alignment.is_some());
        let (day, outside) = if as_it_is {
            (day, 0)
        } else {
            match day.align(library, params, None) {
                Ok(Aligned::Moved { day, outside, .. }) => (*day, outside),
                Ok(Aligned::Refused(refusal)) => {
                    let reason = format!("not aligned onto the library: {refusal}");
                    report.refused.push(refuse(reason));
                    continue;
                }
                Err(e) => {
                    report.refused.push(refuse(e.to_string()));
                    continue;
                }
            }
        };
        match library.ingest(day.label.clone(), &day.map, &day.density) {
            Ok(i) => report.ingested.push(MergedDay {
                index,
                label: day.label,
                layout: i.layout,
                created: i.created,
                alignment: day.alignment,
                outside,
            }),
            Err(AffordanceError::DuplicateDay { label }) => report.duplicates.push((index, label)),
            Err(e) => report.refused.push(refuse(e.to_string())),
        }
    }
    report
}
