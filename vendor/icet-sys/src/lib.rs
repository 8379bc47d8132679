//! Raw bindings to the vendored IceT (vendor/icet-sys/VOLCAST.md): hand-written `extern "C"` declarations for
//! the functions volcast's safe wrapper (`src/distributed/icet.rs`) calls, and the constants it uses. Every
//! type and value is copied from `icet/src/include/IceT.h`, `IceTMPI.h` and the hand-written
//! `icet/include/IceTConfig.h` (LP64: `IceTInt32` is `int`, `IceTUnsignedInt32` is `unsigned int`).
//!
//! IceT keeps one *current context* in a C global (`icetSetContext`); every call below except
//! `icetCreateMPICommunicator`, `icetDestroyMPICommunicator`, `icetCreateContext`, `icetDestroyContext`,
//! `icetGetContext` and `icetSetContext` acts on it. IceT is not thread-safe.
#![no_std]
#![allow(non_camel_case_types, non_snake_case)]

use core::ffi::{c_char, c_int, c_void};

// ---- Basic types (IceT.h, on IceTConfig.h's LP64 typedefs) ----

pub type IceTEnum = u32;
pub type IceTBitField = u32;
pub type IceTDouble = f64;
pub type IceTFloat = f32;
pub type IceTInt = i32;
pub type IceTUInt = u32;
pub type IceTShort = i16;
pub type IceTUShort = u16;
pub type IceTByte = i8;
pub type IceTUByte = u8;
pub type IceTBoolean = u8;
pub type IceTVoid = c_void;
pub type IceTSizeType = i32;

/// `struct IceTContextStruct`, opaque.
#[repr(C)]
pub struct IceTContextStruct {
    _private: [u8; 0],
}
/// `typedef struct IceTContextStruct *IceTContext;`
pub type IceTContext = *mut IceTContextStruct;

/// `struct IceTCommunicatorStruct` (a table of function pointers in C); opaque here, volcast only passes it on.
#[repr(C)]
pub struct IceTCommunicatorStruct {
    _private: [u8; 0],
}
/// `typedef struct IceTCommunicatorStruct *IceTCommunicator;`
pub type IceTCommunicator = *mut IceTCommunicatorStruct;

/// `typedef struct { IceTVoid *opaque_internals; } IceTImage;`, passed and returned by value. The buffer it
/// points to belongs to the IceT context and is reused by the next IceT call that composites.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct IceTImage {
    pub opaque_internals: *mut IceTVoid,
}

// ---- Data types and booleans ----

pub const ICET_BOOLEAN: IceTEnum = 0x8000;
pub const ICET_BYTE: IceTEnum = 0x8001;
pub const ICET_SHORT: IceTEnum = 0x8002;
pub const ICET_INT: IceTEnum = 0x8003;
pub const ICET_FLOAT: IceTEnum = 0x8004;
pub const ICET_DOUBLE: IceTEnum = 0x8005;
pub const ICET_SIZE_TYPE: IceTEnum = ICET_INT;
pub const ICET_POINTER: IceTEnum = 0x8008;
pub const ICET_VOID: IceTEnum = 0x800F;
pub const ICET_NULL: IceTEnum = 0x0000;

pub const ICET_FALSE: IceTBoolean = 0;
pub const ICET_TRUE: IceTBoolean = 1;

// ---- Image formats ----

pub const ICET_IMAGE_COLOR_RGBA_UBYTE: IceTEnum = 0xC001;
pub const ICET_IMAGE_COLOR_RGBA_FLOAT: IceTEnum = 0xC002;
pub const ICET_IMAGE_COLOR_RGB_FLOAT: IceTEnum = 0xC003;
pub const ICET_IMAGE_COLOR_NONE: IceTEnum = 0xC000;

pub const ICET_IMAGE_DEPTH_FLOAT: IceTEnum = 0xD001;
pub const ICET_IMAGE_DEPTH_NONE: IceTEnum = 0xD000;

// ---- Strategies ----

pub const ICET_STRATEGY_DIRECT: IceTEnum = 0x6001;
pub const ICET_STRATEGY_SEQUENTIAL: IceTEnum = 0x6002;
pub const ICET_STRATEGY_SPLIT: IceTEnum = 0x6003;
pub const ICET_STRATEGY_REDUCE: IceTEnum = 0x6004;
pub const ICET_STRATEGY_VTREE: IceTEnum = 0x6005;

pub const ICET_SINGLE_IMAGE_STRATEGY_AUTOMATIC: IceTEnum = 0x7001;
pub const ICET_SINGLE_IMAGE_STRATEGY_BSWAP: IceTEnum = 0x7002;
pub const ICET_SINGLE_IMAGE_STRATEGY_TREE: IceTEnum = 0x7003;
pub const ICET_SINGLE_IMAGE_STRATEGY_RADIXK: IceTEnum = 0x7004;
pub const ICET_SINGLE_IMAGE_STRATEGY_RADIXKR: IceTEnum = 0x7005;
pub const ICET_SINGLE_IMAGE_STRATEGY_BSWAP_FOLDING: IceTEnum = 0x7006;

// ---- Composite modes ----

pub const ICET_COMPOSITE_MODE_Z_BUFFER: IceTEnum = 0x0301;
pub const ICET_COMPOSITE_MODE_BLEND: IceTEnum = 0x0302;

// ---- Diagnostics (icetDiagnostics) ----

pub const ICET_DIAG_OFF: IceTBitField = 0x0000;
pub const ICET_DIAG_ERRORS: IceTBitField = 0x0001;
pub const ICET_DIAG_WARNINGS: IceTBitField = 0x0003;
pub const ICET_DIAG_DEBUG: IceTBitField = 0x0007;
pub const ICET_DIAG_ROOT_NODE: IceTBitField = 0x0000;
pub const ICET_DIAG_ALL_NODES: IceTBitField = 0x0100;
pub const ICET_DIAG_FULL: IceTBitField = 0xFFFF;

// ---- State variables (icetGet*v) ----

pub const ICET_STATE_ENGINE_START: IceTEnum = 0x0000_0000;
pub const ICET_DIAGNOSTIC_LEVEL: IceTEnum = ICET_STATE_ENGINE_START | 0x0001;
pub const ICET_RANK: IceTEnum = ICET_STATE_ENGINE_START | 0x0002;
pub const ICET_NUM_PROCESSES: IceTEnum = ICET_STATE_ENGINE_START | 0x0003;
pub const ICET_BACKGROUND_COLOR: IceTEnum = ICET_STATE_ENGINE_START | 0x0005;
pub const ICET_COLOR_FORMAT: IceTEnum = ICET_STATE_ENGINE_START | 0x0009;
pub const ICET_DEPTH_FORMAT: IceTEnum = ICET_STATE_ENGINE_START | 0x000A;
pub const ICET_NUM_TILES: IceTEnum = ICET_STATE_ENGINE_START | 0x0010;
pub const ICET_TILE_VIEWPORTS: IceTEnum = ICET_STATE_ENGINE_START | 0x0011;
pub const ICET_GLOBAL_VIEWPORT: IceTEnum = ICET_STATE_ENGINE_START | 0x0012;
pub const ICET_STRATEGY: IceTEnum = ICET_STATE_ENGINE_START | 0x0024;
pub const ICET_SINGLE_IMAGE_STRATEGY: IceTEnum = ICET_STATE_ENGINE_START | 0x0025;
pub const ICET_COMPOSITE_MODE: IceTEnum = ICET_STATE_ENGINE_START | 0x0028;
pub const ICET_COMPOSITE_ORDER: IceTEnum = ICET_STATE_ENGINE_START | 0x0029;
pub const ICET_PROCESS_ORDERS: IceTEnum = ICET_STATE_ENGINE_START | 0x002A;
pub const ICET_STRATEGY_SUPPORTS_ORDERING: IceTEnum = ICET_STATE_ENGINE_START | 0x002B;
pub const ICET_FRAME_COUNT: IceTEnum = ICET_STATE_ENGINE_START | 0x002E;
pub const ICET_MAGIC_K: IceTEnum = ICET_STATE_ENGINE_START | 0x0040;
pub const ICET_MAX_IMAGE_SPLIT: IceTEnum = ICET_STATE_ENGINE_START | 0x0041;

pub const ICET_STATE_TIMING_START: IceTEnum = 0x0000_00C0;
pub const ICET_RENDER_TIME: IceTEnum = ICET_STATE_TIMING_START | 0x0001;
pub const ICET_BUFFER_READ_TIME: IceTEnum = ICET_STATE_TIMING_START | 0x0002;
pub const ICET_BUFFER_WRITE_TIME: IceTEnum = ICET_STATE_TIMING_START | 0x0003;
pub const ICET_COMPRESS_TIME: IceTEnum = ICET_STATE_TIMING_START | 0x0004;
pub const ICET_INTERLACE_TIME: IceTEnum = ICET_STATE_TIMING_START | 0x0005;
pub const ICET_COMPARE_TIME: IceTEnum = ICET_STATE_TIMING_START | 0x0006;
pub const ICET_BLEND_TIME: IceTEnum = ICET_COMPARE_TIME;
pub const ICET_COMPOSITE_TIME: IceTEnum = ICET_STATE_TIMING_START | 0x0007;
pub const ICET_COLLECT_TIME: IceTEnum = ICET_STATE_TIMING_START | 0x0008;
pub const ICET_TOTAL_DRAW_TIME: IceTEnum = ICET_STATE_TIMING_START | 0x0009;
/// An `IceTInt`: the bytes this process sent during the last frame.
pub const ICET_BYTES_SENT: IceTEnum = ICET_STATE_TIMING_START | 0x000A;

// ---- Enables (icetEnable / icetDisable / icetIsEnabled) ----

pub const ICET_STATE_ENABLE_START: IceTEnum = 0x0000_0140;
pub const ICET_FLOATING_VIEWPORT: IceTEnum = ICET_STATE_ENABLE_START | 0x0001;
pub const ICET_ORDERED_COMPOSITE: IceTEnum = ICET_STATE_ENABLE_START | 0x0002;
pub const ICET_CORRECT_COLORED_BACKGROUND: IceTEnum = ICET_STATE_ENABLE_START | 0x0003;
pub const ICET_COMPOSITE_ONE_BUFFER: IceTEnum = ICET_STATE_ENABLE_START | 0x0004;
pub const ICET_INTERLACE_IMAGES: IceTEnum = ICET_STATE_ENABLE_START | 0x0005;
pub const ICET_COLLECT_IMAGES: IceTEnum = ICET_STATE_ENABLE_START | 0x0006;
pub const ICET_RENDER_EMPTY_IMAGES: IceTEnum = ICET_STATE_ENABLE_START | 0x0007;

// ---- Errors (icetGetError) ----

pub const ICET_NO_ERROR: IceTEnum = 0x0000_0000;
pub const ICET_SANITY_CHECK_FAIL: IceTEnum = 0xFFFF_FFFF;
pub const ICET_INVALID_ENUM: IceTEnum = 0xFFFF_FFFE;
pub const ICET_BAD_CAST: IceTEnum = 0xFFFF_FFFD;
pub const ICET_OUT_OF_MEMORY: IceTEnum = 0xFFFF_FFFC;
pub const ICET_INVALID_OPERATION: IceTEnum = 0xFFFF_FFFB;
pub const ICET_INVALID_VALUE: IceTEnum = 0xFFFF_FFFA;

extern "C" {
    // ---- IceTMPI.h ----

    /// `IceTCommunicator icetCreateMPICommunicator(MPI_Comm mpi_comm);` IceT duplicates `mpi_comm`
    /// (`MPI_Comm_dup`, collective over it), so the caller's handle need not outlive the result.
    ///
    /// `MPI_Comm` is a pointer (`struct ompi_communicator_t *`) in Open MPI, taken here as `*mut c_void`. From
    /// rsmpi, whose `mpi::ffi::MPI_Comm` is a newtype around that pointer, pass the pointer inside:
    /// `mpi::ffi::RSMPI_COMM_WORLD.0.cast()`, or `mpi::traits::AsRaw::as_raw(&world).0.cast()`. (MPICH's
    /// `MPI_Comm` is an `int`; this declaration is for Open MPI.) Returns null for `MPI_COMM_NULL`.
    pub fn icetCreateMPICommunicator(mpi_comm: *mut c_void) -> IceTCommunicator;
    /// `void icetDestroyMPICommunicator(IceTCommunicator comm);` frees the duplicated MPI communicator; call
    /// it before `MPI_Finalize`.
    pub fn icetDestroyMPICommunicator(comm: IceTCommunicator);

    // ---- Contexts ----

    /// Duplicates `comm` again (the context owns its own copy) and makes the new context current.
    pub fn icetCreateContext(comm: IceTCommunicator) -> IceTContext;
    pub fn icetDestroyContext(context: IceTContext);
    pub fn icetGetContext() -> IceTContext;
    pub fn icetSetContext(context: IceTContext);

    // ---- Tiles and bounds ----

    pub fn icetResetTiles();
    /// Returns the tile's index, or -1 with an error raised.
    pub fn icetAddTile(x: IceTInt, y: IceTInt, width: IceTSizeType, height: IceTSizeType, display_rank: c_int)
        -> c_int;
    pub fn icetBoundingVertices(
        size: IceTInt,
        type_: IceTEnum,
        stride: IceTSizeType,
        count: IceTSizeType,
        pointer: *const IceTVoid,
    );

    // ---- Formats, strategies, modes ----

    pub fn icetSetColorFormat(color_format: IceTEnum);
    pub fn icetSetDepthFormat(depth_format: IceTEnum);
    pub fn icetStrategy(strategy: IceTEnum);
    pub fn icetGetStrategyName() -> *const c_char;
    pub fn icetSingleImageStrategy(strategy: IceTEnum);
    pub fn icetGetSingleImageStrategyName() -> *const c_char;
    pub fn icetCompositeMode(mode: IceTEnum);
    /// `process_ranks` must hold exactly `ICET_NUM_PROCESSES` distinct ranks in `0..ICET_NUM_PROCESSES`, the
    /// frontmost first: IceT indexes an array with each entry unchecked.
    pub fn icetCompositeOrder(process_ranks: *const IceTInt);

    // ---- Compositing ----

    /// Composites pre-rendered buffers (densely packed, `width * height` pixels of the tile's global viewport:
    /// RGBA `f32` x4 or `u8` x4 per the colour format, depth `f32`). The buffers are read during the call
    /// only. A null `valid_pixels_viewport` means every pixel is valid; null matrices mean identity (IceT then
    /// drops any bounding vertices). Returns the composited image on the display process and a null image
    /// elsewhere; the image's buffer belongs to the context.
    pub fn icetCompositeImage(
        color_buffer: *const IceTVoid,
        depth_buffer: *const IceTVoid,
        valid_pixels_viewport: *const IceTInt,
        projection_matrix: *const IceTDouble,
        modelview_matrix: *const IceTDouble,
        background_color: *const IceTFloat,
    ) -> IceTImage;

    // ---- Images ----

    pub fn icetImageNull() -> IceTImage;
    pub fn icetImageIsNull(image: IceTImage) -> IceTBoolean;
    pub fn icetImageGetColorFormat(image: IceTImage) -> IceTEnum;
    pub fn icetImageGetDepthFormat(image: IceTImage) -> IceTEnum;
    pub fn icetImageGetWidth(image: IceTImage) -> IceTSizeType;
    pub fn icetImageGetHeight(image: IceTImage) -> IceTSizeType;
    pub fn icetImageGetNumPixels(image: IceTImage) -> IceTSizeType;
    /// Null (with an error raised) unless the colour format is `ICET_IMAGE_COLOR_RGBA_FLOAT` or RGB float.
    pub fn icetImageGetColorcf(image: IceTImage) -> *const IceTFloat;
    /// Null (with an error raised) unless the depth format is `ICET_IMAGE_DEPTH_FLOAT`.
    pub fn icetImageGetDepthcf(image: IceTImage) -> *const IceTFloat;

    // ---- State ----

    pub fn icetGetDoublev(pname: IceTEnum, params: *mut IceTDouble);
    pub fn icetGetFloatv(pname: IceTEnum, params: *mut IceTFloat);
    pub fn icetGetIntegerv(pname: IceTEnum, params: *mut IceTInt);
    pub fn icetGetBooleanv(pname: IceTEnum, params: *mut IceTBoolean);
    pub fn icetGetEnumv(pname: IceTEnum, params: *mut IceTEnum);
    pub fn icetEnable(pname: IceTEnum);
    pub fn icetDisable(pname: IceTEnum);
    pub fn icetIsEnabled(pname: IceTEnum) -> IceTBoolean;

    // ---- Diagnostics ----

    /// Returns the first error (or warning: IceT records warnings' codes too) raised since the last call, and
    /// clears it. The global is shared by all contexts.
    pub fn icetGetError() -> IceTEnum;
    /// Which diagnostics IceT prints (on stdout): `ICET_DIAG_*` level, or'ed with `ICET_DIAG_ALL_NODES` to
    /// print on every rank rather than rank 0 only.
    pub fn icetDiagnostics(mask: IceTBitField);
    pub fn icetWallTime() -> IceTDouble;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_matches_lp64_icet() {
        assert_eq!(core::mem::size_of::<IceTImage>(), core::mem::size_of::<*mut c_void>());
        assert_eq!(core::mem::size_of::<IceTSizeType>(), 4);
        assert_eq!(core::mem::size_of::<IceTEnum>(), 4);
        assert_eq!(ICET_BYTES_SENT, 0xCA);
        assert_eq!(ICET_ORDERED_COMPOSITE, 0x142);
    }
}
