//! (in progress)
pub struct GeometryImages;
pub struct GeometryImagesOptions;
pub struct SurfaceScale;
pub struct TextureImage;
