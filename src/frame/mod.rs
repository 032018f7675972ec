//! A frame's data: everything one frame of a scene needs that is worked out from the scene, resolved here once,
//! before any pass records, and read by every renderer of it.
//!
//! - `setup`: the frame itself, a scene seen through one billboard: the rays' reach (`geometry::Reach`), the
//!   integration mapped onto them, every term of the field with its energy color, tint and share of the
//!   tolerance; and, resolved when first asked for, the texels' clips and crossings, the objects' light and the
//!   particles' light.
//! - `cache`: where what frames resolved is kept for the next ones: one `FrameCache` a renderer owns (the
//!   viewer's, the headless renderer's, the CPU twin's through its setup), one memory bound, invalidated by
//!   what changed. The live sets' simulations keep their states there too (`FrameCache::scene_at`).
//! - `refine`: which texels of the field are integrated exactly and which predicted from coarser ones (refinement
//!   in image space), the plan the GPU's field pass and the CPU twin both follow.
//! - `resolve`: the objects' and particles' light as a frame's passes read them (`Frame`): resolved before the
//!   frame records (renders, exports), or on threads of their own, the frames drawing stand-ins meanwhile (the
//!   viewer).
//!
//! The GPU passes (`gpu`), the CPU twin (`reference`), the viewer and the exports all take a frame from here, so
//! that none of them works any of it out again; the renderers keep only what lives longer than a frame
//! (pipelines, textures). A new kind of per-frame data is resolved here, beside the rest.

pub mod cache;
pub mod refine;
pub mod resolve;
mod setup;

pub use cache::{Changed, FrameCache};
pub use refine::Refine;
pub use resolve::{Frame, ResolvedObjects, Resolver};
pub use setup::{FrameSetup, Term};
