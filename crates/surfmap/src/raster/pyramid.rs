//! (in progress)
pub struct Pyramid;
pub struct PyramidLevel;
