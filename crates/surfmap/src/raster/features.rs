//! (in progress)
pub struct FeatureCurve;
pub struct FeatureFile;
pub struct FeatureMask;
pub struct FeatureSource;
