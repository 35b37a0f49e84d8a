//! What the GPU methods keep from one frame to the next: the scene on the GPU ([`scene`])
//! and the render targets of one image size ([`targets`]). Everything is created once; a
//! frame writes only what changed ([`crate::scene::Changes`]) and records passes, the same
//! way in every GPU method ([`frame`]).

mod encode;
mod frame;
mod readback;
mod samples;
mod scene;
mod targets;

pub(crate) use frame::{GpuFrame, Readback};
pub(crate) use readback::{assemble, normalized, readback_names};
pub(crate) use samples::SampleCounts;
pub(crate) use scene::{check_limits, GpuScene, LightDraw};
pub(crate) use targets::{frame_timer, rgb_image, Stale, Targets};
