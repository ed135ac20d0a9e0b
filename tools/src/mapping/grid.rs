//! The host occupancy grid: geometry (cell size, origin, size) and trinary cells.
//!
//! Cell `(col, row)` covers `[ox + col·res, ox + (col+1)·res) × [oy + row·res, oy + (row+1)·res)`
//! in the world frame (metres): **row 0 is the bottom** (smallest y), as in the world, and
//! `origin` is the lower-left corner of the lower-left cell, as in map_server's YAML. Only the
//! PGM writer flips rows (image row 0 is the top).

/// Size, cell size and placement of a grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridGeometry {
    /// Cells along x.
    pub width: usize,
    /// Cells along y.
    pub height: usize,
    /// Cell side, metres (> 0).
    pub resolution_m: f64,
    /// World x of the lower-left corner of cell (0, 0), metres.
    pub origin_x_m: f64,
    /// World y of the lower-left corner of cell (0, 0), metres.
    pub origin_y_m: f64,
}

impl GridGeometry {
    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.width * self.height
    }

    /// The cell containing world point `(x, y)` (metres), or `None` off the grid.
    pub fn cell_of(&self, x_m: f64, y_m: f64) -> Option<(usize, usize)> {
        let gx = ((x_m - self.origin_x_m) / self.resolution_m).floor();
        let gy = ((y_m - self.origin_y_m) / self.resolution_m).floor();
        if gx >= 0.0 && gy >= 0.0 && gx < self.width as f64 && gy < self.height as f64 {
            Some((gx as usize, gy as usize))
        } else {
            None
        }
    }

    /// World coordinates of the centre of cell `(col, row)`, metres.
    pub fn cell_center(&self, col: usize, row: usize) -> (f64, f64) {
        (
            self.origin_x_m + (col as f64 + 0.5) * self.resolution_m,
            self.origin_y_m + (row as f64 + 0.5) * self.resolution_m,
        )
    }

    /// Row-major index (row 0 at the bottom) of `(col, row)`, or `None` off the grid.
    pub fn index(&self, col: usize, row: usize) -> Option<usize> {
        (col < self.width && row < self.height).then_some(row * self.width + col)
    }
}

/// map_server's trinary cell state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Cell {
    /// Occupied: PGM 0 when written.
    Occupied,
    /// Free: PGM 254.
    Free,
    /// Unknown: PGM 205.
    Unknown,
}

/// Anything that can say whether a grid cell is occupied: what [`super::ray_cast_grid`] needs.
/// Implemented by [`OccupancyGrid`]; another map type (for example one loaded from a
/// map_server YAML) implements it in a few lines.
pub trait OccupiedCells {
    /// The grid's geometry.
    fn geometry(&self) -> GridGeometry;
    /// True when cell `(col, row)` (row 0 at the bottom) is occupied. Called only with
    /// `col < width`, `row < height`.
    fn is_occupied(&self, col: usize, row: usize) -> bool;
}

/// A trinary occupancy grid (row 0 at the bottom).
#[derive(Clone, Debug, PartialEq)]
pub struct OccupancyGrid {
    geometry: GridGeometry,
    cells: Vec<Cell>,
}

/// Errors building an [`OccupancyGrid`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum GridError {
    /// Width or height is zero, or their product overflows.
    BadSize,
    /// Resolution not finite and > 0, or origin not finite.
    BadGeometry,
    /// The cell vector's length is not `width · height`.
    WrongCellCount,
}

impl std::fmt::Display for GridError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::BadSize => "grid width and height must be > 0 and their product must fit",
            Self::BadGeometry => "resolution must be finite and > 0, origin finite",
            Self::WrongCellCount => "cell count differs from width × height",
        })
    }
}

impl std::error::Error for GridError {}

impl OccupancyGrid {
    /// A grid from its geometry and cells (row-major, row 0 at the bottom).
    ///
    /// # Errors
    /// [`GridError`] when the geometry is invalid or the cell count does not match.
    pub fn new(geometry: GridGeometry, cells: Vec<Cell>) -> Result<Self, GridError> {
        let g = geometry;
        if g.width == 0 || g.height == 0 || g.width.checked_mul(g.height).is_none() {
            return Err(GridError::BadSize);
        }
        if !(g.resolution_m.is_finite()
            && g.resolution_m > 0.0
            && g.origin_x_m.is_finite()
            && g.origin_y_m.is_finite())
        {
            return Err(GridError::BadGeometry);
        }
        if cells.len() != g.cells() {
            return Err(GridError::WrongCellCount);
        }
        Ok(Self { geometry, cells })
    }

    /// For builders that validated the geometry and sized the cells themselves.
    pub(crate) fn from_parts(geometry: GridGeometry, cells: Vec<Cell>) -> Self {
        debug_assert_eq!(cells.len(), geometry.cells());
        Self { geometry, cells }
    }

    /// A grid from text rows, for tests and examples: **first line is the top row**, `#` is
    /// occupied, `.` free, anything else unknown.
    ///
    /// # Errors
    /// [`GridError`] for ragged or empty rows, or bad geometry.
    pub fn from_ascii(
        rows_top_first: &[&str],
        resolution_m: f64,
        origin_m: (f64, f64),
    ) -> Result<Self, GridError> {
        let width = rows_top_first.first().map_or(0, |r| r.chars().count());
        let height = rows_top_first.len();
        let mut cells = Vec::with_capacity(width * height);
        for row in rows_top_first.iter().rev() {
            if row.chars().count() != width {
                return Err(GridError::WrongCellCount);
            }
            cells.extend(row.chars().map(|c| match c {
                '#' => Cell::Occupied,
                '.' => Cell::Free,
                _ => Cell::Unknown,
            }));
        }
        Self::new(
            GridGeometry {
                width,
                height,
                resolution_m,
                origin_x_m: origin_m.0,
                origin_y_m: origin_m.1,
            },
            cells,
        )
    }

    /// The geometry.
    pub fn geometry(&self) -> GridGeometry {
        self.geometry
    }

    /// The cells, row-major, row 0 at the bottom.
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// The state of `(col, row)`, or `None` off the grid.
    pub fn get(&self, col: usize, row: usize) -> Option<Cell> {
        self.geometry
            .index(col, row)
            .and_then(|i| self.cells.get(i).copied())
    }

    /// True when `(col, row)` or one of its 8 neighbours is occupied.
    pub fn occupied_within_one_cell(&self, col: usize, row: usize) -> bool {
        (-1i64..=1).any(|dr| {
            (-1i64..=1).any(|dc| {
                let c = col as i64 + dc;
                let r = row as i64 + dr;
                c >= 0 && r >= 0 && self.get(c as usize, r as usize) == Some(Cell::Occupied)
            })
        })
    }

    /// Counts of (occupied, free, unknown) cells.
    pub fn counts(&self) -> (usize, usize, usize) {
        self.cells.iter().fold((0, 0, 0), |(o, f, u), c| match c {
            Cell::Occupied => (o + 1, f, u),
            Cell::Free => (o, f + 1, u),
            Cell::Unknown => (o, f, u + 1),
        })
    }
}

impl OccupiedCells for OccupancyGrid {
    fn geometry(&self) -> GridGeometry {
        self.geometry
    }

    fn is_occupied(&self, col: usize, row: usize) -> bool {
        self.get(col, row) == Some(Cell::Occupied)
    }
}
