//! `OccupancyGrid`: the ROS occupancy convention (−1 unknown, 0 free … 100 occupied).

use crate::{Cell, Grid, GridGeometry, OccupancyError, Result};

/// The value ROS uses for a cell never observed.
pub const UNKNOWN: i8 = -1;
/// The value of a certainly free cell.
pub const FREE: i8 = 0;
/// The value of a certainly occupied cell.
pub const OCCUPIED: i8 = 100;

/// The three states a cell can be read as.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CellState {
    /// Nothing there.
    Free,
    /// An obstacle.
    Occupied,
    /// Never observed, or observed without a clear verdict.
    Unknown,
}

/// How an occupancy value (0–100) reads as a [`CellState`].
///
/// A value `>= occupied_min` is occupied, a value `<= free_max` is free, anything else
/// (including −1 and values between the two thresholds) is unknown. The defaults (65 and 25)
/// are the ROS 1 `map_saver` thresholds.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StateThresholds {
    /// Smallest value read as occupied.
    pub occupied_min: i8,
    /// Largest value read as free.
    pub free_max: i8,
}

impl Default for StateThresholds {
    fn default() -> Self {
        Self {
            occupied_min: 65,
            free_max: 25,
        }
    }
}

impl StateThresholds {
    /// The thresholds after checking `0 <= free_max < occupied_min <= 100`.
    ///
    /// # Errors
    /// [`OccupancyError::InvalidParameter`] naming the violated rule.
    pub fn check(self) -> Result<Self> {
        if !(0..=100).contains(&self.free_max) {
            return Err(OccupancyError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "free_max",
                    value: self.free_max.into(),
                    rule: "must be in 0..=100",
                },
            ));
        }
        if !(self.free_max < self.occupied_min && self.occupied_min <= 100) {
            return Err(OccupancyError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "occupied_min",
                    value: self.occupied_min.into(),
                    rule: "must be > free_max and <= 100",
                },
            ));
        }
        Ok(self)
    }

    /// The state of a value.
    pub fn state(&self, value: i8) -> CellState {
        if !(0..=100).contains(&value) {
            CellState::Unknown
        } else if value >= self.occupied_min {
            CellState::Occupied
        } else if value <= self.free_max {
            CellState::Free
        } else {
            CellState::Unknown
        }
    }
}

/// An occupancy grid: per cell −1 (unknown) or an occupancy percentage 0–100, as ROS
/// `nav_msgs/OccupancyGrid`, with the thresholds that read values as states.
///
/// ```
/// use haunts_occupancy::{Cell, CellState, GridGeometry, OccupancyGrid};
/// use nalgebra::Point2;
/// let g = GridGeometry::new(0.05, Point2::origin(), 2, 1).unwrap();
/// let map = OccupancyGrid::from_values(g, vec![0, 100]).unwrap();
/// assert_eq!(map.state(Cell::new(1, 0)), Some(CellState::Occupied));
/// assert_eq!(map.probability(Cell::new(0, 0)), Some(0.0));
/// assert_eq!(map.counts(), (1, 1, 0)); // free, occupied, unknown
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "OccupancyGridFields"))]
pub struct OccupancyGrid {
    values: Grid<i8>,
    thresholds: StateThresholds,
}

impl OccupancyGrid {
    /// A grid with every cell unknown.
    pub fn unknown(geometry: GridGeometry) -> Self {
        Self {
            values: Grid::filled(geometry, UNKNOWN),
            thresholds: StateThresholds::default(),
        }
    }

    /// A grid from row-major values (row 0 at the bottom), each −1 or in 0..=100.
    ///
    /// # Errors
    /// [`OccupancyError::DataLength`] for a wrong length; [`OccupancyError::InvalidParameter`]
    /// for a value outside −1..=100.
    pub fn from_values(geometry: GridGeometry, values: Vec<i8>) -> Result<Self> {
        Self::from_grid(Grid::from_vec(geometry, values)?)
    }

    /// A grid from a `Grid<i8>` whose values are each −1 or in 0..=100.
    ///
    /// # Errors
    /// [`OccupancyError::InvalidParameter`] for a value outside −1..=100.
    pub fn from_grid(values: Grid<i8>) -> Result<Self> {
        if let Some(bad) = values.data().iter().find(|v| !(-1..=100).contains(*v)) {
            return Err(OccupancyError::InvalidParameter(
                haunts_core::InvalidParameter {
                    name: "occupancy value",
                    value: (*bad).into(),
                    rule: "must be -1 (unknown) or in 0..=100",
                },
            ));
        }
        Ok(Self {
            values,
            thresholds: StateThresholds::default(),
        })
    }

    /// The same grid read with other thresholds.
    ///
    /// # Errors
    /// As [`StateThresholds::check`].
    pub fn with_thresholds(mut self, thresholds: StateThresholds) -> Result<Self> {
        self.thresholds = thresholds.check()?;
        Ok(self)
    }

    /// The thresholds that read values as states.
    pub fn thresholds(&self) -> StateThresholds {
        self.thresholds
    }
    /// Where the grid lies.
    pub fn geometry(&self) -> &GridGeometry {
        self.values.geometry()
    }
    /// The raw values (−1 or 0..=100).
    pub fn values(&self) -> &Grid<i8> {
        &self.values
    }
    /// The value at `cell`, or `None` outside the grid.
    pub fn value(&self, cell: Cell) -> Option<i8> {
        self.values.get(cell).copied()
    }
    /// Sets the value at `cell`, clamped to −1..=100; returns false outside the grid.
    pub fn set(&mut self, cell: Cell, value: i8) -> bool {
        match self.values.get_mut(cell) {
            Some(v) => {
                *v = value.clamp(UNKNOWN, OCCUPIED);
                true
            }
            None => false,
        }
    }
    /// The state of `cell`, or `None` outside the grid.
    pub fn state(&self, cell: Cell) -> Option<CellState> {
        self.value(cell).map(|v| self.thresholds.state(v))
    }
    /// Occupancy probability of `cell` (value / 100), `None` if unknown or outside.
    pub fn probability(&self, cell: Cell) -> Option<f64> {
        self.value(cell)
            .filter(|v| *v >= 0)
            .map(|v| f64::from(v) / 100.0)
    }
    /// The state of every cell.
    pub fn states(&self) -> Grid<CellState> {
        self.values.map(|v| self.thresholds.state(*v))
    }
    /// `true` where a cell is occupied: the obstacle mask for distance transforms.
    pub fn occupied_mask(&self) -> Grid<bool> {
        self.values
            .map(|v| self.thresholds.state(*v) == CellState::Occupied)
    }
    /// `true` where a cell is free.
    pub fn free_mask(&self) -> Grid<bool> {
        self.values
            .map(|v| self.thresholds.state(*v) == CellState::Free)
    }
    /// Counts of (free, occupied, unknown) cells.
    pub fn counts(&self) -> (usize, usize, usize) {
        self.values
            .data()
            .iter()
            .fold((0, 0, 0), |(f, o, u), v| match self.thresholds.state(*v) {
                CellState::Free => (f + 1, o, u),
                CellState::Occupied => (f, o + 1, u),
                CellState::Unknown => (f, o, u + 1),
            })
    }
}

/// The fields of an [`OccupancyGrid`] as deserialised, before its values are checked.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct OccupancyGridFields {
    values: Grid<i8>,
    thresholds: StateThresholds,
}

#[cfg(feature = "serde")]
impl TryFrom<OccupancyGridFields> for OccupancyGrid {
    type Error = OccupancyError;
    fn try_from(f: OccupancyGridFields) -> Result<Self> {
        Self::from_grid(f.values)?.with_thresholds(f.thresholds)
    }
}
