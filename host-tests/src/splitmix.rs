//! The random data sets of the tests and benches, drawn from the library's own generator
//! [`beamfield::mcl::SplitMix64`] (the pose pickers use [`beamfield::mcl::XorShift64`]
//! directly), so that no second copy of either algorithm exists: [`Draws`] adds the f64 draws
//! the host tests use to `SplitMix64`. The trait lives in the tools
//! ([`beamfield_tools::track::draws`]), whose wheel model draws from it too.

pub use beamfield::mcl::SplitMix64;
pub use beamfield_tools::track::draws::Draws;
