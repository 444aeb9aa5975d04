//! The bounds the input format puts on a scene and a render: each keeps a
//! finite resource (memory, a thread's stack, the process's threads) finite
//! whatever a scene file or the command line asks for. The camera, the
//! conversion of a scene and the render loop all read them, so they live
//! below all three.

/// The largest image rendered (2^28 pixels, about 16k × 16k): the frame
/// (40 bytes a pixel, which the EXR writer takes over as its channels) is
/// held in memory.
pub const MAX_PIXELS: u64 = 1 << 28;

/// The most worker threads a render starts.
pub const MAX_THREADS: usize = 1024;

/// The deepest nesting of groups. JSON files cannot get near it (serde_json
/// stops at 128 levels of brackets, about 60 groups) but a `SceneFile` built
/// in code could, and flattening recurses once per level.
pub const MAX_GROUP_DEPTH: usize = 100;

/// The deepest nesting of definitions (a definition placing one placing
/// another ...): each level of a query recurses into the definition it
/// places, on the calling thread's stack.
pub const MAX_DEFINITION_DEPTH: usize = 32;

/// The largest `settings.max_depth`: shading recurses once per bounce, so an
/// unbounded depth could overflow a worker thread's stack.
pub const MAX_BOUNCES: u32 = 64;

/// The most samples per pixel (`settings.spp`, `--spp`): a pixel's samples
/// are counted in a `u32` channel and their random numbers keyed by the
/// sample's number.
pub const MAX_SPP: u32 = 1 << 24;
