//! A layout of the library as Nav2 consumes it: the composite as a static map (for a
//! `StaticLayer`), the costmap with the affordance layer (as `haunts maps` saves it), and a
//! speed-filter mask with its `nav2_msgs/CostmapFilterInfo` (slower where people are).
//!
//! # The speed mask
//! Nav2's speed filter reads a mask value `v` of a cell as no limit when `v` is 0 and as the
//! limit `base + multiplier · v` (percent of the robot's maximum speed, for
//! [`CostmapFilterInfo::SPEED_PERCENT`]) when `v` is in 1..=100. The mask here is the
//! layout's density of people relative to the density at which the costmap's affordance
//! layer saturates ([`ServedLayout::scale`]): `v = ⌈100 · min(1, d / scale)⌉`, so a cell where
//! nobody was seen (or too few visits to say, NaN) has no limit, and with
//! `base = 100`, `multiplier = −(100 − min_percent) / 100` the robot slows linearly with the
//! density down to `min_percent` at the busiest cells.
//!
//! The layer is the layout's time-independent affordance: the library keeps no model of the
//! hour (the daily rhythm is learnt by the main job from its detections, not stored in a
//! library), so "slower where people are *at the current hour*" is not served yet.

use haunts::bag::convert;
use haunts::bag::msg;
use haunts::occupancy::{Grid, OccupancyGrid};
use haunts::pipeline::serve::ServedLayout;

use crate::wire::CostmapFilterInfo;

/// How the maps are served.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct MapParams {
    /// The frame of the maps (the library's; default `map`).
    pub frame: String,
    /// The speed at the busiest cells, percent of the maximum (default 30).
    pub min_speed_percent: f64,
    /// The mask's topic, written into the filter info (default `/haunts/speed_mask`).
    pub mask_topic: String,
}

impl Default for MapParams {
    fn default() -> Self {
        Self {
            frame: "map".into(),
            min_speed_percent: 30.0,
            mask_topic: "/haunts/speed_mask".into(),
        }
    }
}

impl MapParams {
    /// Sets [`MapParams::min_speed_percent`].
    pub fn with_min_speed_percent(mut self, percent: f64) -> Self {
        self.min_speed_percent = percent;
        self
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`haunts::core::InvalidParameter`] for a minimum speed outside `[1, 100]` percent
    /// (Nav2 reads a limit of 0 as no limit).
    pub fn check(self) -> Result<Self, haunts::core::InvalidParameter> {
        if !(1.0..=100.0).contains(&self.min_speed_percent) {
            return Err(haunts::core::InvalidParameter {
                name: "min_speed_percent",
                value: self.min_speed_percent,
                rule: "must be from 1 to 100",
            });
        }
        Ok(self)
    }
}

/// A layout's maps as messages.
#[derive(Debug, Clone, PartialEq)]
pub struct LayoutMessages {
    /// The composite (ROS map values 100, 0, −1).
    pub map: msg::OccupancyGrid,
    /// The costmap with the affordance layer, in Nav2's translation to occupancy values
    /// (what `haunts maps` saves as `layout_N_costmap`).
    pub costmap: msg::OccupancyGrid,
    /// The speed mask (see the [module docs](self)).
    pub speed_mask: msg::OccupancyGrid,
    /// The speed filter's info.
    pub filter_info: CostmapFilterInfo,
}

/// The messages of `served`, stamped `seconds`.
pub fn layout_messages(served: &ServedLayout, params: &MapParams, seconds: f64) -> LayoutMessages {
    let frame = params.frame.as_str();
    LayoutMessages {
        map: convert::occupancy_grid_msg(&served.map, seconds, frame),
        costmap: convert::occupancy_grid_msg(
            &served.with_layer.to_occupancy_grid(),
            seconds,
            frame,
        ),
        speed_mask: convert::occupancy_grid_msg(
            &speed_mask(&served.density, served.scale),
            seconds,
            frame,
        ),
        filter_info: CostmapFilterInfo {
            header: convert::header(seconds, frame),
            type_: CostmapFilterInfo::SPEED_PERCENT,
            filter_mask_topic: params.mask_topic.clone(),
            base: 100.0,
            multiplier: (-(100.0 - params.min_speed_percent) / 100.0) as f32,
        },
    }
}

/// The speed mask of `density` saturating at `scale` (see the [module docs](self)).
pub fn speed_mask(density: &Grid<f64>, scale: f64) -> OccupancyGrid {
    let values = density.map(|&d| {
        let share = if d.is_finite() && d > 0.0 && scale > 0.0 {
            (d / scale).min(1.0)
        } else {
            0.0
        };
        (100.0 * share).ceil() as i8
    });
    // Every value is in 0..=100 by construction.
    OccupancyGrid::from_grid(values).unwrap_or_else(|_| OccupancyGrid::unknown(*density.geometry()))
}

/// The speed limit Nav2's speed filter reads from mask value `v` (percent; `None`: no limit).
pub fn speed_limit(info: &CostmapFilterInfo, v: i8) -> Option<f64> {
    (v > 0).then(|| f64::from(info.base) + f64::from(info.multiplier) * f64::from(v))
}

#[cfg(test)]
mod tests {
    use super::*;
    use haunts::occupancy::GridGeometry;
    use haunts::occupancy::nalgebra::Point2;

    #[test]
    fn the_mask_slows_linearly_with_the_density() {
        let g = GridGeometry::new(1.0, Point2::origin(), 5, 1).unwrap();
        let density = Grid::from_vec(g, vec![f64::NAN, 0.0, 0.5, 2.0, 9.0]).unwrap();
        let mask = speed_mask(&density, 2.0);
        assert_eq!(mask.values().data(), [0, 0, 25, 100, 100]);
        let info = CostmapFilterInfo {
            base: 100.0,
            multiplier: -0.7,
            ..CostmapFilterInfo::default()
        };
        let limits: Vec<Option<f64>> = mask
            .values()
            .data()
            .iter()
            .map(|&v| speed_limit(&info, v))
            .collect();
        assert_eq!(limits[..2], [None, None]);
        assert!((limits[2].unwrap() - 82.5).abs() < 1e-4);
        assert!((limits[4].unwrap() - 30.0).abs() < 1e-4);
    }

    #[test]
    fn min_speed_is_checked() {
        assert!(
            MapParams::default()
                .with_min_speed_percent(0.0)
                .check()
                .is_err()
        );
        assert!(
            MapParams::default()
                .with_min_speed_percent(30.0)
                .check()
                .is_ok()
        );
    }
}
