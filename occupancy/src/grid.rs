//! `Grid<T>`: any per-cell quantity laid out on a [`GridGeometry`], row 0 at the bottom.

use nalgebra::Point2;

use crate::{Cell, GridGeometry, OccupancyError, Result};

/// Values of type `T`, one per cell of a geometry, row-major with row 0 at the bottom
/// (the ROS `nav_msgs/OccupancyGrid` layout).
///
/// ```
/// use haunts_occupancy::{Cell, Grid, GridGeometry};
/// use nalgebra::Point2;
/// let geometry = GridGeometry::new(1.0, Point2::origin(), 3, 2).unwrap();
/// let grid = Grid::from_fn(geometry, |c| c.col + 10 * c.row);
/// assert_eq!(grid[Cell::new(2, 1)], 12);
/// assert_eq!(grid.at_world(Point2::new(0.5, 1.5)), Some(&10));
/// assert_eq!(grid.row(1), &[10, 11, 12]);
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(
        try_from = "GridFields<T>",
        bound(deserialize = "T: serde::Deserialize<'de>")
    )
)]
pub struct Grid<T> {
    geometry: GridGeometry,
    data: Vec<T>,
}

impl<T> Grid<T> {
    /// A grid over `geometry` with the given row-major data (row 0 at the bottom).
    ///
    /// # Errors
    /// [`OccupancyError::DataLength`] unless `data.len() == geometry.len()`.
    pub fn from_vec(geometry: GridGeometry, data: Vec<T>) -> Result<Self> {
        if data.len() != geometry.len() {
            return Err(OccupancyError::DataLength {
                expected: geometry.len(),
                found: data.len(),
            });
        }
        Ok(Self { geometry, data })
    }

    /// A grid whose value at each cell is `f(cell)`, evaluated in row-major order.
    pub fn from_fn(geometry: GridGeometry, mut f: impl FnMut(Cell) -> T) -> Self {
        // Row by row, so that no cell's column and row cost a division.
        let mut data = Vec::with_capacity(geometry.len());
        for row in 0..geometry.height() {
            data.extend((0..geometry.width()).map(|col| f(Cell::new(col, row))));
        }
        Self { geometry, data }
    }

    /// Where the grid lies.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }
    /// Row-major values, row 0 at the bottom.
    pub fn data(&self) -> &[T] {
        &self.data
    }
    /// Mutable row-major values.
    pub fn data_mut(&mut self) -> &mut [T] {
        &mut self.data
    }
    /// Number of columns.
    pub fn width(&self) -> usize {
        self.geometry.width()
    }
    /// Number of rows.
    pub fn height(&self) -> usize {
        self.geometry.height()
    }
    /// The value at `cell`, or `None` outside the grid.
    pub fn get(&self, cell: Cell) -> Option<&T> {
        self.geometry.index(cell).map(|i| &self.data[i])
    }
    /// The mutable value at `cell`, or `None` outside the grid.
    pub fn get_mut(&mut self, cell: Cell) -> Option<&mut T> {
        self.geometry.index(cell).map(|i| &mut self.data[i])
    }
    /// The value of the cell holding world point `p`, or `None` outside the grid.
    pub fn at_world(&self, p: Point2<f64>) -> Option<&T> {
        self.geometry.world_to_cell(p).and_then(|c| self.get(c))
    }
    /// Row `row` (0 = bottom).
    ///
    /// # Panics
    /// When `row >= height`, a programming error.
    pub fn row(&self, row: usize) -> &[T] {
        let w = self.width();
        &self.data[row * w..(row + 1) * w]
    }
    /// Rows from the bottom up.
    pub fn rows(&self) -> std::slice::ChunksExact<'_, T> {
        self.data.chunks_exact(self.width())
    }
    /// Every cell with its value, in row-major order.
    pub fn cells(&self) -> impl Iterator<Item = (Cell, &T)> + '_ {
        // Column and row counted along, so that no cell costs a division (the iterator's
        // exact length is kept for `collect`).
        let w = self.width();
        let (mut col, mut row) = (0, 0);
        self.data.iter().map(move |v| {
            let cell = Cell::new(col, row);
            col += 1;
            if col == w {
                col = 0;
                row += 1;
            }
            (cell, v)
        })
    }
    /// A grid of the same geometry with `f` applied to every value.
    pub fn map<U>(&self, f: impl FnMut(&T) -> U) -> Grid<U> {
        Grid {
            geometry: self.geometry,
            data: self.data.iter().map(f).collect(),
        }
    }
}

impl<T: Clone> Grid<T> {
    /// A grid over `geometry` with every cell set to `value`.
    pub fn filled(geometry: GridGeometry, value: T) -> Self {
        Self {
            geometry,
            data: vec![value; geometry.len()],
        }
    }
}

impl<T> std::ops::Index<Cell> for Grid<T> {
    type Output = T;
    /// # Panics
    /// When `cell` is outside the grid, a programming error; use [`Grid::get`] otherwise.
    fn index(&self, cell: Cell) -> &T {
        assert!(
            self.geometry.contains(cell),
            "cell {cell:?} outside the grid"
        );
        &self.data[cell.row * self.width() + cell.col]
    }
}

impl<T> std::ops::IndexMut<Cell> for Grid<T> {
    /// # Panics
    /// When `cell` is outside the grid, a programming error; use [`Grid::get_mut`] otherwise.
    fn index_mut(&mut self, cell: Cell) -> &mut T {
        assert!(
            self.geometry.contains(cell),
            "cell {cell:?} outside the grid"
        );
        let w = self.width();
        &mut self.data[cell.row * w + cell.col]
    }
}

/// The fields of a [`Grid`] as deserialised, before the data length is checked.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct GridFields<T> {
    geometry: GridGeometry,
    data: Vec<T>,
}

#[cfg(feature = "serde")]
impl<T> TryFrom<GridFields<T>> for Grid<T> {
    type Error = OccupancyError;
    fn try_from(f: GridFields<T>) -> Result<Self> {
        Self::from_vec(f.geometry, f.data)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_length_is_checked() {
        let g = GridGeometry::new(1.0, Point2::origin(), 3, 2).unwrap();
        assert!(matches!(
            Grid::from_vec(g, vec![0u8; 5]),
            Err(OccupancyError::DataLength {
                expected: 6,
                found: 5
            })
        ));
        let grid = Grid::from_vec(g, (0..6).collect::<Vec<u8>>()).unwrap();
        assert_eq!(grid.row(0), &[0, 1, 2]);
        assert_eq!(grid[Cell::new(0, 1)], 3);
        assert_eq!(grid.get(Cell::new(3, 0)), None);
        assert_eq!(grid.cells().nth(4), Some((Cell::new(1, 1), &4)));
    }
}
