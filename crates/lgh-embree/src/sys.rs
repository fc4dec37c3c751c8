//! The few declarations of Embree 3's C API (`embree3/rtcore*.h`, version 3.13) that the
//! wrapper calls, written out by hand so that every one can be read against the header.
//!
//! The struct layouts are those of a library configured with `RTC_MAX_INSTANCE_LEVEL_COUNT`
//! 1 and `EMBREE_MIN_WIDTH` 0 (Embree's defaults, Debian's build); `build.rs` reads the
//! library's `rtcore_config.h` and links nothing else. The size assertions at the end fail
//! the build if a declaration drifts from the header's.

use std::ffi::{c_char, c_int, c_uint, c_void};

/// `RTCDevice`: an opaque, reference-counted handle.
pub type RtcDevice = *mut c_void;
/// `RTCScene`: an opaque, reference-counted handle.
pub type RtcScene = *mut c_void;
/// `RTCGeometry`: an opaque, reference-counted handle.
pub type RtcGeometry = *mut c_void;

/// `RTC_INVALID_GEOMETRY_ID`.
pub const INVALID_GEOMETRY_ID: c_uint = c_uint::MAX;
/// `RTC_GEOMETRY_TYPE_TRIANGLE`.
pub const GEOMETRY_TYPE_TRIANGLE: c_int = 0;
/// `RTC_BUFFER_TYPE_INDEX`.
pub const BUFFER_TYPE_INDEX: c_int = 0;
/// `RTC_BUFFER_TYPE_VERTEX`.
pub const BUFFER_TYPE_VERTEX: c_int = 1;
/// `RTC_FORMAT_UINT3` (`RTC_FORMAT_UINT` = 0x5001, then 2, 3, 4 components).
pub const FORMAT_UINT3: c_int = 0x5003;
/// `RTC_FORMAT_FLOAT3` (`RTC_FORMAT_FLOAT` = 0x9001).
pub const FORMAT_FLOAT3: c_int = 0x9003;
/// `RTC_SCENE_FLAG_DYNAMIC`.
pub const SCENE_FLAG_DYNAMIC: c_int = 1;
/// `RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT`.
pub const CONTEXT_FLAG_INCOHERENT: c_int = 0;
/// `RTC_INTERSECT_CONTEXT_FLAG_COHERENT`.
pub const CONTEXT_FLAG_COHERENT: c_int = 1;
/// `RTC_DEVICE_PROPERTY_RAY_STREAM_SUPPORTED`.
pub const DEVICE_PROPERTY_RAY_STREAM_SUPPORTED: c_int = 35;

/// `struct RTCRay` (16-byte aligned).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RtcRay {
    /// Origin x, y, z.
    pub org: [f32; 3],
    /// Start of the ray segment.
    pub tnear: f32,
    /// Direction x, y, z (need not be unit length).
    pub dir: [f32; 3],
    /// Time for motion blur.
    pub time: f32,
    /// End of the segment; set to the hit distance, or to -inf by an occlusion query that
    /// found something.
    pub tfar: f32,
    /// Ray mask.
    pub mask: c_uint,
    /// Ray id.
    pub id: c_uint,
    /// Ray flags.
    pub flags: c_uint,
}

/// `struct RTCHit` (16-byte aligned), with one instance level.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RtcHit {
    /// Unnormalised geometric normal.
    pub ng: [f32; 3],
    /// Barycentric u (weight of vertex 1).
    pub u: f32,
    /// Barycentric v (weight of vertex 2).
    pub v: f32,
    /// Primitive id.
    pub prim_id: c_uint,
    /// Geometry id, `INVALID_GEOMETRY_ID` for a miss.
    pub geom_id: c_uint,
    /// Instance id stack (one level).
    pub inst_id: [c_uint; 1],
}

/// `struct RTCRayHit`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct RtcRayHit {
    /// The ray.
    pub ray: RtcRay,
    /// The hit.
    pub hit: RtcHit,
}

/// `struct RTCIntersectContext` with one instance level and no minimum width, initialised as
/// the header's inline `rtcInitIntersectContext` does.
#[repr(C)]
#[derive(Debug)]
pub struct RtcIntersectContext {
    /// `enum RTCIntersectContextFlags`.
    pub flags: c_int,
    /// `RTCFilterFunctionN`, a nullable function pointer; always null here.
    pub filter: *const c_void,
    /// Instance id stack (one level).
    pub inst_id: [c_uint; 1],
}

impl RtcIntersectContext {
    /// `rtcInitIntersectContext` with the given flags.
    pub fn new(flags: c_int) -> Self {
        Self {
            flags,
            filter: std::ptr::null(),
            inst_id: [INVALID_GEOMETRY_ID],
        }
    }
}

/// `struct RTCFilterFunctionNArguments`: N candidate hits, structure of arrays.
#[repr(C)]
#[derive(Debug)]
pub struct RtcFilterFunctionNArguments {
    /// N ints: -1 for a hit to be filtered, 0 for an inactive lane; set 0 to reject.
    pub valid: *mut c_int,
    /// The geometry's user data (`rtcSetGeometryUserData`).
    pub geometry_user_ptr: *mut c_void,
    /// The query's context.
    pub context: *mut RtcIntersectContext,
    /// `RTCRayN`: N rays, structure of arrays.
    pub ray: *mut c_void,
    /// `RTCHitN`: N hits, structure of arrays (`RTCHitN_u` at float 3N + i, `RTCHitN_v` at
    /// 4N + i, `RTCHitN_primID` at word 5N + i).
    pub hit: *mut c_void,
    /// N.
    pub n: c_uint,
}

/// `RTCFilterFunctionN`.
pub type RtcFilterFunctionN = unsafe extern "C" fn(args: *const RtcFilterFunctionNArguments);

unsafe extern "C" {
    pub fn rtcNewDevice(config: *const c_char) -> RtcDevice;
    pub fn rtcGetDeviceError(device: RtcDevice) -> c_int;
    pub fn rtcGetDeviceProperty(device: RtcDevice, prop: c_int) -> isize;

    pub fn rtcNewScene(device: RtcDevice) -> RtcScene;
    pub fn rtcReleaseScene(scene: RtcScene);
    pub fn rtcSetSceneBuildQuality(scene: RtcScene, quality: c_int);
    pub fn rtcSetSceneFlags(scene: RtcScene, flags: c_int);
    pub fn rtcAttachGeometry(scene: RtcScene, geometry: RtcGeometry) -> c_uint;
    pub fn rtcCommitScene(scene: RtcScene);

    pub fn rtcNewGeometry(device: RtcDevice, kind: c_int) -> RtcGeometry;
    pub fn rtcReleaseGeometry(geometry: RtcGeometry);
    pub fn rtcSetGeometryBuildQuality(geometry: RtcGeometry, quality: c_int);
    pub fn rtcSetNewGeometryBuffer(
        geometry: RtcGeometry,
        kind: c_int,
        slot: c_uint,
        format: c_int,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;
    pub fn rtcCommitGeometry(geometry: RtcGeometry);
    pub fn rtcSetGeometryUserData(geometry: RtcGeometry, ptr: *mut c_void);
    pub fn rtcSetGeometryIntersectFilterFunction(
        geometry: RtcGeometry,
        filter: Option<RtcFilterFunctionN>,
    );
    pub fn rtcSetGeometryOccludedFilterFunction(
        geometry: RtcGeometry,
        filter: Option<RtcFilterFunctionN>,
    );

    pub fn rtcIntersect1(
        scene: RtcScene,
        context: *mut RtcIntersectContext,
        rayhit: *mut RtcRayHit,
    );
    pub fn rtcOccluded1(scene: RtcScene, context: *mut RtcIntersectContext, ray: *mut RtcRay);
    pub fn rtcIntersect1M(
        scene: RtcScene,
        context: *mut RtcIntersectContext,
        rayhit: *mut RtcRayHit,
        m: c_uint,
        byte_stride: usize,
    );
    pub fn rtcOccluded1M(
        scene: RtcScene,
        context: *mut RtcIntersectContext,
        ray: *mut RtcRay,
        m: c_uint,
        byte_stride: usize,
    );
}

// The header's sizes: RTCRay 12 floats, RTCHit 8 words padded to 16 bytes, the context two
// words and a pointer on a 64-bit target.
const _: () = assert!(std::mem::size_of::<RtcRay>() == 48);
const _: () = assert!(std::mem::size_of::<RtcHit>() == 32);
const _: () = assert!(std::mem::size_of::<RtcRayHit>() == 80);
const _: () = assert!(std::mem::align_of::<RtcRayHit>() == 16);
const _: () = assert!(std::mem::size_of::<RtcFilterFunctionNArguments>() == 48);
