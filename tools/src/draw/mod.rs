//! Drawing: line charts, heat maps, field figures, scan overlays and track pictures, all written
//! as PNG files for people to look at.
pub mod field_figure;
pub mod heat_map;
pub mod map_picture;
pub mod overlay;
pub mod plot;
pub mod polar;
pub mod tracks;
