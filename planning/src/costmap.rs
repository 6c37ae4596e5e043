//! The costmap (Nav2 cost values on a `Grid<u8>`) and the stack of layers it is built from.

use haunts_occupancy::{Cell, Grid, GridGeometry};
use nalgebra::Point2;

use crate::{PlanningError, Result};

/// Cost of a cell with nothing in it.
pub const FREE_SPACE: u8 = 0;
/// Highest cost of a cell the robot's centre may enter (Nav2 `MAX_NON_OBSTACLE`).
pub const MAX_NON_OBSTACLE: u8 = 252;
/// A cell within the robot's inscribed radius of an obstacle: the robot's centre there collides
/// (Nav2 `INSCRIBED_INFLATED_OBSTACLE`).
pub const INSCRIBED_INFLATED_OBSTACLE: u8 = 253;
/// A cell holding an obstacle (Nav2 `LETHAL_OBSTACLE`).
pub const LETHAL_OBSTACLE: u8 = 254;
/// A cell never observed (Nav2 `NO_INFORMATION`).
pub const NO_INFORMATION: u8 = 255;

/// Traversal costs of a grid, with the Nav2 conventions: `0` free, `1..=252` increasingly
/// undesirable, [`INSCRIBED_INFLATED_OBSTACLE`] (253), [`LETHAL_OBSTACLE`] (254) and [`NO_INFORMATION`] (255).
///
/// Planners never enter inscribed or lethal cells; unknown cells follow their
/// [`UnknownPolicy`](crate::UnknownPolicy).
///
/// ```
/// use haunts_occupancy::{Cell, Grid, GridGeometry};
/// use haunts_planning::{Costmap, LETHAL_OBSTACLE};
/// let geometry = GridGeometry::new(0.1, nalgebra::Point2::origin(), 3, 2).unwrap();
/// let costmap = Costmap::new(Grid::from_fn(geometry, |c| if c.col == 1 { LETHAL_OBSTACLE } else { 0 }));
/// assert_eq!(costmap.cost(Cell::new(1, 1)), Some(LETHAL_OBSTACLE));
/// assert_eq!(costmap.cost_at_world(nalgebra::Point2::new(0.05, 0.05)), Some(0));
/// ```
///
/// With the `serde` feature a costmap (de)serialises as its [`Grid`] (`geometry` and row-major
/// `data`); deserialising checks that the data has one cost per cell.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(transparent))]
pub struct Costmap {
    costs: Grid<u8>,
}

impl Costmap {
    /// A costmap of the given costs (every `u8` is a valid cost).
    pub fn new(costs: Grid<u8>) -> Self {
        Self { costs }
    }
    /// A costmap with every cell at `cost`.
    pub fn filled(geometry: GridGeometry, cost: u8) -> Self {
        Self::new(Grid::filled(geometry, cost))
    }
    /// Where the costmap lies.
    pub fn geometry(&self) -> &GridGeometry {
        self.costs.geometry()
    }
    /// The costs as a grid.
    pub fn grid(&self) -> &Grid<u8> {
        &self.costs
    }
    /// The costs as a mutable grid.
    pub fn grid_mut(&mut self) -> &mut Grid<u8> {
        &mut self.costs
    }
    /// Row-major costs, row 0 at the bottom.
    pub fn data(&self) -> &[u8] {
        self.costs.data()
    }
    /// The cost of `cell`, or `None` outside the costmap.
    pub fn cost(&self, cell: Cell) -> Option<u8> {
        self.costs.get(cell).copied()
    }
    /// The costmap as a `nav_msgs/OccupancyGrid`, translated as Nav2's costmap publisher
    /// translates it: free 0 → 0, lethal → 100, inscribed → 99, unknown → −1, and the costs
    /// between 1 and 252 spread linearly over 1–98. Save it with
    /// [`haunts_occupancy::save_map`] in raw mode to give it to a `map_server`, or publish it
    /// for RViz and Foxglove.
    ///
    /// # Example
    /// ```
    /// use haunts_occupancy::{Grid, GridGeometry};
    /// use haunts_planning::{Costmap, INSCRIBED_INFLATED_OBSTACLE, LETHAL_OBSTACLE, NO_INFORMATION};
    /// let g = GridGeometry::new(0.1, nalgebra::Point2::origin(), 6, 1).unwrap();
    /// let costmap = Costmap::new(Grid::from_vec(g, vec![0, 1, 252, INSCRIBED_INFLATED_OBSTACLE, LETHAL_OBSTACLE, NO_INFORMATION]).unwrap());
    /// assert_eq!(costmap.to_occupancy_grid().values().data(), &[0, 1, 98, 99, 100, -1]);
    /// ```
    pub fn to_occupancy_grid(&self) -> haunts_occupancy::OccupancyGrid {
        let values = self.costs.map(|&c| match c {
            0 => 0,
            LETHAL_OBSTACLE => 100,
            INSCRIBED_INFLATED_OBSTACLE => 99,
            NO_INFORMATION => -1,
            c => (1 + (u32::from(c) - 1) * 97 / 251) as i8,
        });
        // Every value lies in −1..=100, one per cell of the costmap's own geometry.
        haunts_occupancy::OccupancyGrid::from_values(*self.geometry(), values.data().to_vec())
            .unwrap_or_else(|_| haunts_occupancy::OccupancyGrid::unknown(*self.geometry()))
    }

    /// The cost of the cell holding world point `p`, or `None` outside the costmap.
    pub fn cost_at_world(&self, p: Point2<f64>) -> Option<u8> {
        self.costs.at_world(p).copied()
    }

    /// The cell nearest to world point `p` (by its centre) among those a path may end in
    /// (cost below [`INSCRIBED_INFLATED_OBSTACLE`]) whose centre lies within `within` metres of `p`; ties go to
    /// the first in row-major order. `None` when there is none that close (`p` deep inside an
    /// obstacle, or far outside the costmap), or when `p` is not finite or `within` is NaN or
    /// negative: snapping a goal a user clicked onto a wall to the free space beside it.
    ///
    /// # Complexity
    /// O(cells within `within` of `p`), at most the costmap's cells.
    ///
    /// ```
    /// use haunts_occupancy::{Cell, Grid, GridGeometry};
    /// use haunts_planning::{Costmap, LETHAL_OBSTACLE};
    /// let geometry = GridGeometry::new(1.0, nalgebra::Point2::origin(), 5, 1).unwrap();
    /// let costmap = Costmap::new(Grid::from_vec(geometry, vec![0, LETHAL_OBSTACLE, LETHAL_OBSTACLE, LETHAL_OBSTACLE, 0])?);
    /// let p = nalgebra::Point2::new(3.2, 0.5);
    /// assert_eq!(costmap.nearest_free(p, 2.0), Some(Cell::new(4, 0)));
    /// assert_eq!(costmap.nearest_free(p, 1.2), None);
    /// assert_eq!(costmap.nearest_free(p, f64::INFINITY), Some(Cell::new(4, 0)));
    /// # Ok::<(), haunts_occupancy::OccupancyError>(())
    /// ```
    pub fn nearest_free(&self, p: Point2<f64>, within: f64) -> Option<Cell> {
        let g = self.geometry();
        let (x, y) = g.world_to_grid(p);
        if !(x.is_finite() && y.is_finite()) || within.is_nan() || within < 0.0 {
            return None;
        }
        // The cells whose index lies within `within` of p's, clipped to the costmap (in f64,
        // so that far-away points and huge distances cannot overflow).
        let reach = within / g.resolution() + 1.0;
        let span = |v: f64, n: usize| {
            let (lo, hi) = ((v - reach).floor().max(0.0), (v + reach).ceil());
            let hi = hi.min(n as f64 - 1.0);
            (lo <= hi).then_some((lo as usize, hi as usize))
        };
        let ((c0, c1), (r0, r1)) = (span(x, g.width())?, span(y, g.height())?);
        let mut best: Option<(f64, Cell)> = None;
        for row in r0..=r1 {
            for col in c0..=c1 {
                let cell = Cell::new(col, row);
                let d = (g.cell_center(cell) - p).norm();
                if d <= within
                    && best.is_none_or(|(b, _)| d < b)
                    && self
                        .cost(cell)
                        .is_some_and(|v| v < INSCRIBED_INFLATED_OBSTACLE)
                {
                    best = Some((d, cell));
                }
            }
        }
        best.map(|(_, cell)| cell)
    }
}

/// One layer of a [`LayeredCostmap`]: it reads the costs the layers below it produced and
/// writes its own.
///
/// The stack always rebuilds a costmap from [`FREE_SPACE`] through every layer in order, so a layer
/// never sees its own earlier output and a changed layer leaves no stale cost behind.
pub trait Layer: Send + Sync + std::fmt::Debug {
    /// Writes this layer's costs into `costs`, on top of the layers below.
    ///
    /// # Errors
    /// Whatever the layer cannot do, typically [`PlanningError::GeometryMismatch`] when its
    /// data lies on another grid than `costs`.
    fn apply(&self, costs: &mut Costmap) -> Result<()>;
}

/// Index of a layer in a [`LayeredCostmap`], returned by [`LayeredCostmap::push`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct LayerId(usize);

impl LayerId {
    /// Position of the layer in the stack (0 = bottom, applied first).
    pub fn index(self) -> usize {
        self.0
    }
}

/// A costmap defined by its geometry and an ordered stack of [`Layer`]s, as a Nav2 layered
/// costmap: typically a [`StaticLayer`](crate::StaticLayer), an
/// [`InflationLayer`](crate::InflationLayer) and [`DensityLayer`](crate::DensityLayer)s.
///
/// There is no cached master grid to go stale: [`LayeredCostmap::build`] starts from an all
/// [`FREE_SPACE`] grid and applies every layer in order, so replacing a layer (say, a density layer
/// rasterised from a newer map) and building again gives exactly the costmap a fresh stack
/// would.
///
/// ```
/// use haunts_occupancy::{Grid, GridGeometry};
/// use haunts_planning::{DensityLayer, DensityLayerParams, LayeredCostmap};
/// let geometry = GridGeometry::new(0.5, nalgebra::Point2::origin(), 4, 1).unwrap();
/// let people = Grid::from_vec(geometry, vec![0.0, 1.0, 0.5, 0.0]).unwrap();
/// let mut stack = LayeredCostmap::new(geometry);
/// let density = stack.push(DensityLayer::new(people, DensityLayerParams::default().with_weight(100.0))?);
/// assert_eq!(stack.build()?.data(), &[0, 100, 50, 0]);
///
/// // The people moved: replace the layer; nothing of the old one remains.
/// let moved = Grid::from_vec(geometry, vec![1.0, 0.0, 0.0, 0.0]).unwrap();
/// stack.replace(density, DensityLayer::new(moved, DensityLayerParams::default().with_weight(100.0))?)?;
/// assert_eq!(stack.build()?.data(), &[100, 0, 0, 0]);
/// # Ok::<(), haunts_planning::PlanningError>(())
/// ```
#[derive(Debug)]
pub struct LayeredCostmap {
    geometry: GridGeometry,
    layers: Vec<Box<dyn Layer>>,
}

impl LayeredCostmap {
    /// An empty stack over `geometry` (it builds an all-free costmap).
    pub fn new(geometry: GridGeometry) -> Self {
        Self {
            geometry,
            layers: Vec::new(),
        }
    }

    /// The stack with `layer` added on top (builder style).
    pub fn with_layer(mut self, layer: impl Layer + 'static) -> Self {
        self.push(layer);
        self
    }

    /// Adds `layer` on top of the stack; returns its id for [`LayeredCostmap::replace`].
    pub fn push(&mut self, layer: impl Layer + 'static) -> LayerId {
        self.layers.push(Box::new(layer));
        LayerId(self.layers.len() - 1)
    }

    /// Puts `layer` in place of layer `id`, returning the old one.
    ///
    /// # Errors
    /// [`PlanningError::NoSuchLayer`] when `id` is not a layer of this stack.
    pub fn replace(&mut self, id: LayerId, layer: impl Layer + 'static) -> Result<Box<dyn Layer>> {
        let layers = self.layers.len();
        let slot = self
            .layers
            .get_mut(id.0)
            .ok_or(PlanningError::NoSuchLayer {
                index: id.0,
                layers,
            })?;
        Ok(std::mem::replace(slot, Box::new(layer)))
    }

    /// Where the costmap lies.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// The layers, bottom first.
    pub fn layers(&self) -> impl Iterator<Item = &dyn Layer> + '_ {
        self.layers.iter().map(|l| &**l)
    }

    /// The costmap: an all-[`FREE_SPACE`] grid with every layer applied in order.
    ///
    /// # Errors
    /// The first error of a layer's [`Layer::apply`].
    ///
    /// # Complexity
    /// The sum of the layers' costs, each O(cells) for the layers of this crate.
    pub fn build(&self) -> Result<Costmap> {
        let mut costs = Costmap::filled(self.geometry, FREE_SPACE);
        self.apply_layers(&mut costs)?;
        Ok(costs)
    }

    /// [`LayeredCostmap::build`] into an existing costmap of the same geometry, reusing its
    /// memory: every cell is reset to [`FREE_SPACE`] first.
    ///
    /// # Errors
    /// [`PlanningError::GeometryMismatch`] when `out` lies on another grid; as
    /// [`LayeredCostmap::build`] otherwise.
    pub fn build_into(&self, out: &mut Costmap) -> Result<()> {
        crate::error::same_geometry("output costmap", &self.geometry, out.geometry())?;
        out.grid_mut().data_mut().fill(FREE_SPACE);
        self.apply_layers(out)
    }

    fn apply_layers(&self, costs: &mut Costmap) -> Result<()> {
        self.layers.iter().try_for_each(|layer| layer.apply(costs))
    }
}
