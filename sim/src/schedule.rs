//! Which furniture layout each day uses: runs of days with one layout, a new layout at the
//! start of each run (seed 000 Fig. 10/12: the room is rearranged every week or two).

use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};

use crate::error::{Result, SimError};
use crate::rng::{Stream, stream_seed};

/// The largest day index the simulator accepts (about 2700 years of days).
pub const MAX_DAY: usize = 1_000_000;

/// How layouts change between days.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ScheduleParams {
    /// Runs of `min_run..=max_run` days (uniform); every run brings a layout different from
    /// the previous one: the layouts not yet seen in order first, then uniformly among the
    /// others. With `max_run` ≤ 14 and 5 layouts, 70 days always see every layout.
    Runs {
        /// Shortest run of days with one layout (≥ 1).
        min_run: usize,
        /// Longest run (≥ `min_run`).
        max_run: usize,
    },
    /// An explicit layout index per day, repeated cyclically.
    Fixed(Vec<usize>),
}

impl Default for ScheduleParams {
    fn default() -> Self {
        Self::Runs {
            min_run: 4,
            max_run: 12,
        }
    }
}

impl ScheduleParams {
    /// The parameters if they are usable with `layouts` layouts.
    ///
    /// # Errors
    /// [`SimError::InvalidParameter`] for `min_run == 0`, `max_run < min_run`, an empty fixed
    /// list or a fixed index not below `layouts`; [`SimError::NoLayouts`] for `layouts == 0`.
    pub fn check(self, layouts: usize) -> Result<Self> {
        if layouts == 0 {
            return Err(SimError::NoLayouts);
        }
        match &self {
            Self::Runs { min_run, max_run } => {
                if *min_run == 0 {
                    return Err(SimError::InvalidParameter(haunts_core::InvalidParameter {
                        name: "schedule.min_run",
                        value: 0.0,
                        rule: "must be >= 1",
                    }));
                }
                if max_run < min_run {
                    return Err(SimError::InvalidParameter(haunts_core::InvalidParameter {
                        name: "schedule.max_run",
                        value: *max_run as f64,
                        rule: "must be >= min_run",
                    }));
                }
            }
            Self::Fixed(list) => {
                if list.is_empty() {
                    return Err(SimError::InvalidParameter(haunts_core::InvalidParameter {
                        name: "schedule.fixed",
                        value: 0.0,
                        rule: "at least one day",
                    }));
                }
                if let Some(&bad) = list.iter().find(|&&l| l >= layouts) {
                    return Err(SimError::InvalidParameter(haunts_core::InvalidParameter {
                        name: "schedule.fixed",
                        value: bad as f64,
                        rule: "must be a layout index below the number of layouts",
                    }));
                }
            }
        }
        Ok(self)
    }

    /// The layout of every day `0..days`, drawn from `seed`'s schedule stream (the same
    /// for every prefix: day `d`'s layout does not depend on how many days are asked for).
    ///
    /// # Errors
    /// As [`ScheduleParams::check`]; [`SimError::DayOutOfRange`] beyond [`MAX_DAY`].
    pub fn layouts(&self, seed: u64, layouts: usize, days: usize) -> Result<Vec<usize>> {
        self.clone().check(layouts)?;
        if days > MAX_DAY + 1 {
            return Err(SimError::DayOutOfRange {
                day: days - 1,
                max: MAX_DAY,
            });
        }
        let mut out = Vec::with_capacity(days);
        match self {
            Self::Fixed(list) => out.extend((0..days).map(|d| list[d % list.len()])),
            Self::Runs { min_run, max_run } => {
                let mut rng =
                    Xoshiro256PlusPlus::seed_from_u64(stream_seed(seed, 0, Stream::Schedule, 0));
                let (mut current, mut next_unseen) = (0usize, 1usize);
                while out.len() < days {
                    let run = rng.random_range(*min_run..=*max_run);
                    out.extend(std::iter::repeat_n(current, run.min(days - out.len())));
                    if layouts > 1 {
                        current = if next_unseen < layouts {
                            next_unseen += 1;
                            next_unseen - 1
                        } else {
                            let k = rng.random_range(0..layouts - 1);
                            if k >= current { k + 1 } else { k }
                        };
                    }
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_change_layout_and_prefixes_agree() {
        let s = ScheduleParams::default();
        let long = s.layouts(3, 5, 70).unwrap();
        let short = s.layouts(3, 5, 20).unwrap();
        assert_eq!(&long[..20], &short[..]);
        let mut runs = 1;
        for w in long.windows(2) {
            if w[0] != w[1] {
                runs += 1;
            }
        }
        assert!(runs >= 70 / 12);
        assert!(s.layouts(3, 0, 5).is_err());
        assert!(
            ScheduleParams::Runs {
                min_run: 3,
                max_run: 2
            }
            .check(5)
            .is_err()
        );
        assert!(ScheduleParams::Fixed(vec![0, 7]).check(5).is_err());
        assert_eq!(
            ScheduleParams::Fixed(vec![1, 2]).layouts(0, 3, 5).unwrap(),
            vec![1, 2, 1, 2, 1]
        );
    }
}
