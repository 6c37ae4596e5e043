//! The cost model every grid planner shares: step costs from cell costs, and which cells a
//! path may enter.

use crate::costmap::{INSCRIBED_INFLATED_OBSTACLE, MAX_NON_OBSTACLE, NO_INFORMATION};
use crate::error::rule;
use crate::{Costmap, Endpoint, PlanningError, Result};
use haunts_occupancy::Cell;

/// What planners do with [`NO_INFORMATION`] (255) cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum UnknownPolicy {
    /// Unknown cells are obstacles (never entered, and no corner is cut past them).
    #[default]
    Forbid,
    /// Unknown cells are traversable at the given cost (`0..=252`).
    Allow(u8),
}

/// The cost model of the grid planners.
///
/// A step from a cell to one of its 8 neighbours costs `L · (1 + cost_weight · c / 252)`, where
/// `L` is the step's length in metres (one or √2 cells) and `c` the cost of the cell entered
/// (in the spirit of Nav2's Smac 2-D planner and its `cost_travel_multiplier`). Inscribed (253)
/// and lethal (254) cells are never entered; unknown cells (255) follow [`UnknownPolicy`]. A
/// diagonal step is allowed only when both cells it passes between are enterable (no corner
/// cutting).
///
/// Every step costs at least its length, so the octile distance is an admissible and
/// consistent heuristic and A* returns optimal paths.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct SearchParams {
    /// Weight of the costmap's costs: 0 plans the shortest path through non-obstacle cells.
    pub cost_weight: f64,
    /// What to do with unknown cells.
    pub unknown: UnknownPolicy,
}

impl Default for SearchParams {
    /// Cost weight 2 (the default of Smac 2-D's `cost_travel_multiplier`), unknown cells
    /// forbidden.
    fn default() -> Self {
        Self {
            cost_weight: 2.0,
            unknown: UnknownPolicy::Forbid,
        }
    }
}

impl SearchParams {
    /// Sets the weight of the costmap's costs.
    pub fn with_cost_weight(mut self, weight: f64) -> Self {
        self.cost_weight = weight;
        self
    }
    /// Sets the policy for unknown cells.
    pub fn with_unknown(mut self, policy: UnknownPolicy) -> Self {
        self.unknown = policy;
        self
    }

    /// The parameters, after checking a finite `cost_weight >= 0` and an
    /// [`UnknownPolicy::Allow`] cost of at most 252.
    ///
    /// # Errors
    /// [`PlanningError::InvalidParameter`] naming the first rule broken.
    pub fn check(self) -> Result<Self> {
        let w = self.cost_weight;
        rule(
            "cost_weight",
            w,
            w.is_finite() && w >= 0.0,
            "must be finite and >= 0",
        )?;
        if let UnknownPolicy::Allow(c) = self.unknown {
            rule(
                "unknown cost",
                c.into(),
                c <= MAX_NON_OBSTACLE,
                "must be <= 252",
            )?;
        }
        Ok(self)
    }

    /// The factor `1 + cost_weight · c / 252` of every cost `c`, infinite for cells that are
    /// never entered.
    pub(crate) fn factors(&self) -> Factors {
        let mut table = [f64::INFINITY; 256];
        for (c, f) in table
            .iter_mut()
            .enumerate()
            .take(usize::from(INSCRIBED_INFLATED_OBSTACLE))
        {
            *f = 1.0 + self.cost_weight * c as f64 / f64::from(MAX_NON_OBSTACLE);
        }
        if let UnknownPolicy::Allow(c) = self.unknown {
            table[usize::from(NO_INFORMATION)] = table[usize::from(c)];
        }
        Factors(table)
    }
}

/// Step-length multipliers per cost value (`INFINITY` = not enterable).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Factors(pub(crate) [f64; 256]);

impl Factors {
    /// The multiplier of entering a cell of cost `c`.
    #[inline]
    pub(crate) fn of(&self, c: u8) -> f64 {
        self.0[usize::from(c)]
    }

    /// Checks that `cell` is inside `costmap` and enterable, returning its row-major index.
    pub(crate) fn endpoint(
        &self,
        costmap: &Costmap,
        endpoint: Endpoint,
        cell: Cell,
    ) -> Result<usize> {
        let g = costmap.geometry();
        let index = g.index(cell).ok_or(PlanningError::CellOutsideMap {
            endpoint,
            cell,
            width: g.width(),
            height: g.height(),
        })?;
        let cost = costmap.data()[index];
        if self.of(cost).is_finite() {
            Ok(index)
        } else if cost == NO_INFORMATION {
            Err(PlanningError::InUnknown { endpoint, cell })
        } else {
            Err(PlanningError::InObstacle {
                endpoint,
                cell,
                cost,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_are_checked() {
        assert!(matches!(
            SearchParams::default().with_cost_weight(f64::NAN).check(),
            Err(PlanningError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "cost_weight",
                    ..
                }
            ))
        ));
        assert!(matches!(
            SearchParams::default().with_cost_weight(-1.0).check(),
            Err(PlanningError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "cost_weight",
                    ..
                }
            ))
        ));
        assert!(matches!(
            SearchParams::default()
                .with_unknown(UnknownPolicy::Allow(253))
                .check(),
            Err(PlanningError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "unknown cost",
                    ..
                }
            ))
        ));
    }

    #[test]
    fn factors_follow_the_formula_and_the_unknown_policy() {
        let f = SearchParams::default().with_cost_weight(2.0).factors();
        assert_eq!(f.of(0), 1.0);
        assert_eq!(f.of(126), 2.0);
        assert_eq!(f.of(252), 3.0);
        assert!(f.of(253).is_infinite() && f.of(254).is_infinite() && f.of(255).is_infinite());
        let allow = SearchParams::default()
            .with_cost_weight(2.0)
            .with_unknown(UnknownPolicy::Allow(126))
            .factors();
        assert_eq!(allow.of(255), 2.0);
    }
}
