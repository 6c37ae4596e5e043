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

/// Why [`merge_into_file`] did not merge.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LibraryMergeError {
    /// Another merge held the library's lock for longer than the wait.
    #[error(
        "{library}: another merge into this library is running ({source}; its lock is {lock}); \
         run this merge again when it is done, or wait longer"
    )]
    Busy {
        /// The library.
        library: std::path::PathBuf,
        /// Its lock file.
        lock: std::path::PathBuf,
        /// What the wait ended with.
        source: std::io::Error,
    },
    /// The lock file could not be made or taken.
    #[error("{path}: cannot {step}: {source}")]
    Lock {
        /// The lock file.
        path: std::path::PathBuf,
        /// What was being done.
        step: &'static str,
        /// The cause.
        source: std::io::Error,
    },
    /// No library yet, and no day to start one from.
    #[error("{library}: no day to merge")]
    NoDays {
        /// The library.
        library: std::path::PathBuf,
    },
    /// The library could not be loaded, made or saved.
    #[error(transparent)]
    Library(#[from] AffordanceError),
}

/// What [`merge_into_file`] did.
#[derive(Debug, Clone)]
pub struct LibraryMerge {
    /// The library after the merge (as saved, when it was).
    pub library: LayoutLibrary,
    /// What became of each day.
    pub report: MergeReport,
    /// Whether the library file existed before.
    pub existed: bool,
    /// Whether the library was saved (a day joined, or the library is new).
    pub saved: bool,
}

/// The parameters of a new library (`haunts merge`'s and a live session's): a layout's
/// density is known where its days' beams crossed a cell at least 30 times, and its
/// composite keeps what 35 % of its days saw (the `pipeline` example's choice, explained
/// there).
pub fn library_params() -> crate::affordance::LayoutParams {
    crate::affordance::LayoutParams::default()
        .with_min_visits(30)
        .with_composite_min_fraction(0.35)
}

/// `days` into the layout library at `path`, as `haunts merge` does it: one merge at a time
/// (an advisory lock on the library's sidecar `.NAME.lock`, waited for up to `wait`, held
/// from before the load to after the save), the library loaded, or made with `params` on the
/// cells of the earliest day when the file does not exist, the days merged
/// ([`merge_days`]), and the library saved once, atomically (a crash leaves the old library
/// or the new one), unless nothing joined an existing library.
///
/// # Errors
/// [`LibraryMergeError::Busy`] after the wait; the lock's, the library's and the save's
/// errors; [`LibraryMergeError::NoDays`] for no day and no library.
pub fn merge_into_file(
    path: &std::path::Path,
    days: Vec<DayArtifact>,
    params: crate::affordance::LayoutParams,
    register: &RegisterParams,
    wait: std::time::Duration,
) -> Result<LibraryMerge, LibraryMergeError> {
    let _lock = crate::occupancy::atomic::lock(path, wait, |lock, step, source| {
        if source.kind() == std::io::ErrorKind::TimedOut {
            LibraryMergeError::Busy {
                library: path.to_path_buf(),
                lock: lock.to_path_buf(),
                source,
            }
        } else {
            LibraryMergeError::Lock {
                path: lock.to_path_buf(),
                step,
                source,
            }
        }
    })?;
    let existed = path.exists();
    let mut library = if existed {
        LayoutLibrary::load(path)?
    } else {
        // The earliest day's cells and frame are the new library's.
        let first =
            days.iter()
                .min_by(|a, b| recording_order(a, b))
                .ok_or(LibraryMergeError::NoDays {
                    library: path.to_path_buf(),
                })?;
        LayoutLibrary::new(*first.map.geometry(), params)?
    };
    let report = merge_days(&mut library, days, register);
    let saved = !report.ingested.is_empty() || !existed;
    if saved {
        library.save(path)?;
    }
    Ok(LibraryMerge {
        library,
        report,
        existed,
        saved,
    })
}
