//! Indirect-light estimators over one photon set, run by the frame engine after the eye
//! G-buffer: today the raster photon volumes of ISPM ([`volumes::Volumes`]).

pub mod volumes;

pub use volumes::Volumes;
