//! The design layer: from a plant and the designer's choices to every gain the controller needs.

pub mod assumptions;
pub mod place;

pub use place::{place, PlaceError};

/// The designer's choices. (placeholder)
pub struct DesignSpec;
/// Observer choice. (placeholder)
pub enum ObserverChoice {}
/// The design. (placeholder)
pub struct Design;
/// Design errors. (placeholder)
#[derive(Debug, thiserror::Error)]
pub enum DesignError {}
