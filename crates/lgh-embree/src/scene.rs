//! The committed triangle scene and its queries, over the C API in `sys`.

use std::ffi::c_uint;
use std::sync::OnceLock;

use crate::sys;
use crate::{BuildQuality, Error, Hit, HitFilter, Ray};

/// Rays handed to Embree per stream call: 64 rays are 3 KB (5 KB with hits) on the stack,
/// initialised per call.
const STREAM: usize = 64;

/// The process's Embree device, created on first use and never released, and whether the
/// library was built with ray streams (`EMBREE_RAY_PACKETS`; without them the stream calls
/// are answered one ray at a time here).
struct Device(sys::RtcDevice, bool);

// SAFETY: an RTCDevice is a reference-counted handle whose functions Embree documents as
// thread-safe (creating scenes and geometries from several threads, each its own objects);
// the handle itself is never released, so it outlives every use on every thread.
unsafe impl Send for Device {}
// SAFETY: as for `Send`: shared use only creates new objects, which Embree allows
// concurrently, and reads the calling thread's own error code.
unsafe impl Sync for Device {}

/// The device, created on the first call (with Embree's defaults: the best instruction set of
/// the processor, one build thread per hardware thread).
fn device() -> Result<&'static Device, Error> {
    static DEVICE: OnceLock<Result<Device, Error>> = OnceLock::new();
    DEVICE
        .get_or_init(|| {
            // SAFETY: a null configuration string is documented as "use the defaults".
            let d = unsafe { sys::rtcNewDevice(std::ptr::null()) };
            if d.is_null() {
                // SAFETY: rtcGetDeviceError accepts a null device and then returns the error
                // of the failed rtcNewDevice on this thread.
                return Err(Error::Device(unsafe { sys::rtcGetDeviceError(d) }));
            }
            // SAFETY: `d` is a live device; the property code is the header's.
            let streams =
                unsafe { sys::rtcGetDeviceProperty(d, sys::DEVICE_PROPERTY_RAY_STREAM_SUPPORTED) };
            Ok(Device(d, streams != 0))
        })
        .as_ref()
        .map_err(Clone::clone)
}

impl Device {
    /// The first error recorded on this thread since the last call (0: none); clears it.
    fn error(&self) -> i32 {
        // SAFETY: `self.0` is a live device (never released).
        unsafe { sys::rtcGetDeviceError(self.0) }
    }
}

/// Releases a geometry handle when dropped (on every path out of [`Scene::new`]).
struct GeometryRef(sys::RtcGeometry);

impl Drop for GeometryRef {
    fn drop(&mut self) {
        // SAFETY: the handle came from rtcNewGeometry and this is the one reference this
        // struct owns; a scene it was attached to holds a reference of its own.
        unsafe { sys::rtcReleaseGeometry(self.0) }
    }
}

/// A committed Embree scene of one triangle mesh.
///
/// It is built and committed by [`Scene::new`] and never changed afterwards, so any number of
/// threads may query it at once.
pub struct Scene {
    handle: sys::RtcScene,
    triangles: usize,
    streams: bool,
    /// The filter Embree calls through the geometry's user data: boxed, so that its address
    /// stays fixed, and dropped after the scene is released (fields drop after `drop`).
    filter: Option<Box<HitFilter>>,
}

// SAFETY: the scene is committed in `new` and never modified; Embree documents that
// rtcIntersect1/rtcOccluded1 and the stream calls rtcIntersect1M/rtcOccluded1M may be called
// from any number of threads concurrently on a committed scene. Release happens only in
// `drop`, which has exclusive access.
unsafe impl Send for Scene {}
// SAFETY: as for `Send`: `&Scene` exposes only those thread-safe queries.
unsafe impl Sync for Scene {}

impl std::fmt::Debug for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("embree::Scene")
            .field("triangles", &self.triangles)
            .finish()
    }
}

impl Drop for Scene {
    fn drop(&mut self) {
        // SAFETY: the handle came from rtcNewScene, this is its one owner, and no query can
        // be running (drop has exclusive access).
        unsafe { sys::rtcReleaseScene(self.handle) }
    }
}

/// Embree's `RTCBuildQuality` and scene flags for a [`BuildQuality`].
fn quality_codes(q: BuildQuality) -> (i32, i32) {
    match q {
        BuildQuality::Low => (0, sys::SCENE_FLAG_DYNAMIC),
        BuildQuality::Medium => (1, 0),
        BuildQuality::High => (2, 0),
    }
}

/// A ray for Embree, or `None` for one Embree must not see (non-finite origin or direction,
/// an end that is NaN, negative or zero): such a ray hits nothing.
#[inline]
fn rtc_ray(r: &Ray) -> Option<sys::RtcRay> {
    let finite = r.origin.iter().chain(&r.dir).all(|c| c.is_finite());
    (finite && r.t_max > 0.0).then_some(sys::RtcRay {
        org: r.origin,
        tnear: 0.0,
        dir: r.dir,
        time: 0.0,
        tfar: r.t_max,
        mask: c_uint::MAX,
        id: 0,
        flags: 0,
    })
}

/// An empty hit record (no geometry).
const NO_HIT: sys::RtcHit = sys::RtcHit {
    ng: [0.0; 3],
    u: 0.0,
    v: 0.0,
    prim_id: sys::INVALID_GEOMETRY_ID,
    geom_id: sys::INVALID_GEOMETRY_ID,
    inst_id: [sys::INVALID_GEOMETRY_ID],
};

/// The hit an intersection query left in `rh`.
#[inline]
fn hit_of(rh: &sys::RtcRayHit) -> Option<Hit> {
    (rh.hit.geom_id != sys::INVALID_GEOMETRY_ID).then_some(Hit {
        t: rh.ray.tfar,
        triangle: rh.hit.prim_id,
        uv: [rh.hit.u, rh.hit.v],
    })
}

impl Scene {
    /// Builds the BVH over `triangles` (indices into `vertices`) with the given quality, in
    /// parallel on Embree's own threads, and commits it.
    ///
    /// # Errors
    /// [`Error::Mesh`] for an index out of range or a non-finite vertex; [`Error::Device`]
    /// if Embree cannot start on this processor; [`Error::Build`] if Embree fails (out of
    /// memory).
    pub fn new(
        vertices: &[[f32; 3]],
        triangles: &[[u32; 3]],
        quality: BuildQuality,
    ) -> Result<Self, Error> {
        Self::with_filter(vertices, triangles, quality, None)
    }

    /// [`Scene::new`] with a filter that every candidate hit of every query must pass
    /// (Embree's intersection and occlusion filter functions, which see hits in any order
    /// and as many as the traversal meets).
    ///
    /// # Errors
    /// As [`Scene::new`].
    pub fn with_filter(
        vertices: &[[f32; 3]],
        triangles: &[[u32; 3]],
        quality: BuildQuality,
        filter: Option<HitFilter>,
    ) -> Result<Self, Error> {
        crate::check_mesh(vertices, triangles)?;
        let dev = device()?;
        dev.error(); // clear anything left on this thread
        let (q, flags) = quality_codes(quality);
        // SAFETY: `dev.0` is a live device.
        let handle = unsafe { sys::rtcNewScene(dev.0) };
        if handle.is_null() {
            return Err(Error::Build(dev.error()));
        }
        let scene = Self {
            handle,
            triangles: triangles.len(),
            streams: dev.1,
            filter: filter.map(Box::new),
        };
        // SAFETY: a live scene not yet committed, owned by this thread; codes from the header.
        unsafe {
            sys::rtcSetSceneBuildQuality(handle, q);
            sys::rtcSetSceneFlags(handle, flags);
        }
        if !triangles.is_empty() {
            // SAFETY: `dev.0` is a live device; the type is the header's triangle mesh.
            let geom =
                GeometryRef(unsafe { sys::rtcNewGeometry(dev.0, sys::GEOMETRY_TYPE_TRIANGLE) });
            if geom.0.is_null() {
                return Err(Error::Build(dev.error()));
            }
            // SAFETY: a live geometry owned by this thread.
            unsafe { sys::rtcSetGeometryBuildQuality(geom.0, q) };
            // SAFETY: Embree allocates a buffer of `vertices.len()` items of 12 bytes (with
            // the padding its vector loads need) and returns it, or null on failure; nothing
            // else can reach it before the commit.
            let vb = unsafe {
                sys::rtcSetNewGeometryBuffer(
                    geom.0,
                    sys::BUFFER_TYPE_VERTEX,
                    0,
                    sys::FORMAT_FLOAT3,
                    12,
                    vertices.len(),
                )
            }
            .cast::<[f32; 3]>();
            // SAFETY: as above, `triangles.len()` items of 12 bytes.
            let ib = unsafe {
                sys::rtcSetNewGeometryBuffer(
                    geom.0,
                    sys::BUFFER_TYPE_INDEX,
                    0,
                    sys::FORMAT_UINT3,
                    12,
                    triangles.len(),
                )
            }
            .cast::<[u32; 3]>();
            if vb.is_null() || ib.is_null() {
                return Err(Error::Build(dev.error()));
            }
            // SAFETY: `vb` and `ib` are non-null, hold exactly `len` items of the slices'
            // element type (12 bytes, 4-byte aligned, which Embree's allocation exceeds),
            // and cannot overlap the caller's slices (Embree allocated them).
            unsafe {
                std::ptr::copy_nonoverlapping(vertices.as_ptr(), vb, vertices.len());
                std::ptr::copy_nonoverlapping(triangles.as_ptr(), ib, triangles.len());
            }
            if let Some(f) = &scene.filter {
                let user = std::ptr::from_ref::<HitFilter>(f).cast_mut().cast();
                // SAFETY: a live geometry not yet committed; `user` points at the boxed
                // filter the scene owns, which lives as long as the scene (it is dropped
                // after the scene is released) and is only read, from any thread (it is
                // Sync); `filter_hits` reads it as that type.
                unsafe {
                    sys::rtcSetGeometryUserData(geom.0, user);
                    sys::rtcSetGeometryIntersectFilterFunction(geom.0, Some(filter_hits));
                    sys::rtcSetGeometryOccludedFilterFunction(geom.0, Some(filter_hits));
                }
            }
            // SAFETY: a live geometry with both buffers set, attached to a live uncommitted
            // scene; the scene takes a reference of its own, so the guard's release is fine.
            unsafe {
                sys::rtcCommitGeometry(geom.0);
                sys::rtcAttachGeometry(handle, geom.0);
            }
        }
        // SAFETY: a live scene, built on this thread; Embree's own threads join the build.
        unsafe { sys::rtcCommitScene(handle) };
        match dev.error() {
            0 => Ok(scene),
            code => Err(Error::Build(code)),
        }
    }

    /// Number of triangles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.triangles
    }

    /// True if there is no triangle.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.triangles == 0
    }

    /// The closest hit along `ray` (t in [0, `t_max`]), `rtcIntersect1`.
    #[inline]
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut rh = sys::RtcRayHit {
            ray: rtc_ray(ray)?,
            hit: NO_HIT,
        };
        let mut ctx = sys::RtcIntersectContext::new(sys::CONTEXT_FLAG_INCOHERENT);
        // SAFETY: a committed scene (thread-safe queries), a context initialised as
        // rtcInitIntersectContext does, and a valid ray/hit record that lives across the call.
        unsafe { sys::rtcIntersect1(self.handle, &mut ctx, &mut rh) };
        hit_of(&rh)
    }

    /// True if anything lies on `ray`'s segment (any-hit), `rtcOccluded1`.
    #[inline]
    #[must_use]
    pub fn occluded(&self, ray: &Ray) -> bool {
        let Some(mut r) = rtc_ray(ray) else {
            return false;
        };
        let mut ctx = sys::RtcIntersectContext::new(sys::CONTEXT_FLAG_INCOHERENT);
        // SAFETY: as in `intersect`, with a valid ray record.
        unsafe { sys::rtcOccluded1(self.handle, &mut ctx, &mut r) };
        r.tfar == f32::NEG_INFINITY
    }

    /// Occlusion of many rays at once through Embree's stream call (`rtcOccluded1M`, 64 rays a
    /// call): `out[i]` is true if something lies on `rays[i]`. `coherent` tells Embree that the
    /// rays share origins or directions (e.g. one point's rays to many lights), so that it
    /// traces them as packets.
    ///
    /// # Panics
    /// If `out` is shorter than `rays` (a caller's bug, not an input).
    pub fn occluded_many(&self, rays: &[Ray], coherent: bool, out: &mut [bool]) {
        assert!(out.len() >= rays.len(), "one output per ray");
        if !self.streams {
            for (r, o) in rays.iter().zip(out) {
                *o = self.occluded(r);
            }
            return;
        }
        let flag = context_flag(coherent);
        let trace = |buf: &mut [sys::RtcRay]| {
            let mut ctx = sys::RtcIntersectContext::new(flag);
            // SAFETY: a committed scene (thread-safe queries), an initialised context, and
            // `buf.len()` <= 64 valid contiguous ray records of 48 bytes each (the stride
            // given).
            unsafe {
                sys::rtcOccluded1M(
                    self.handle,
                    &mut ctx,
                    buf.as_mut_ptr(),
                    buf.len() as c_uint,
                    std::mem::size_of::<sys::RtcRay>(),
                );
            }
        };
        stream(
            rays,
            out,
            false,
            |r| r,
            trace,
            |r| r.tfar == f32::NEG_INFINITY,
        );
    }

    /// Closest hits of many rays at once through Embree's stream call (`rtcIntersect1M`, 64
    /// rays a call); `coherent` as in [`Scene::occluded_many`].
    ///
    /// # Panics
    /// If `out` is shorter than `rays` (a caller's bug, not an input).
    pub fn intersect_many(&self, rays: &[Ray], coherent: bool, out: &mut [Option<Hit>]) {
        assert!(out.len() >= rays.len(), "one output per ray");
        if !self.streams {
            for (r, o) in rays.iter().zip(out) {
                *o = self.intersect(r);
            }
            return;
        }
        let flag = context_flag(coherent);
        let trace = |buf: &mut [sys::RtcRayHit]| {
            let mut ctx = sys::RtcIntersectContext::new(flag);
            // SAFETY: as in `occluded_many`, with `buf.len()` ray/hit records of 80 bytes each.
            unsafe {
                sys::rtcIntersect1M(
                    self.handle,
                    &mut ctx,
                    buf.as_mut_ptr(),
                    buf.len() as c_uint,
                    std::mem::size_of::<sys::RtcRayHit>(),
                );
            }
        };
        let record = |ray| sys::RtcRayHit { ray, hit: NO_HIT };
        stream(rays, out, None, record, trace, hit_of);
    }
}

/// Embree's filter function of a scene with a [`HitFilter`]: clears `valid` of every
/// candidate hit the filter refuses, so that the traversal goes on past it.
unsafe extern "C" fn filter_hits(args: *const sys::RtcFilterFunctionNArguments) {
    // SAFETY: Embree passes a valid arguments record that lives for the call.
    let args = unsafe { &*args };
    // SAFETY: the user data is the boxed filter of the scene being queried
    // (`Scene::with_filter` set it; the scene outlives its queries).
    let filter = unsafe { &*args.geometry_user_ptr.cast::<HitFilter>() };
    let n = args.n as usize;
    let hit = args.hit.cast::<f32>();
    for i in 0..n {
        // SAFETY: `valid` holds N ints and `hit` N lanes of each of RTCHitN's fields
        // (structure of arrays: u at float 3N + i, v at 4N + i, primID at word 5N + i, the
        // header's RTCHitN_u, RTCHitN_v, RTCHitN_primID); the lanes are only read here, and
        // `valid` of lane i is written by this call alone.
        unsafe {
            let valid = args.valid.add(i);
            if *valid == 0 {
                continue;
            }
            let (u, v) = (*hit.add(3 * n + i), *hit.add(4 * n + i));
            let prim = *hit.add(5 * n + i).cast::<u32>();
            if !filter(prim, [u, v]) {
                *valid = 0;
            }
        }
    }
}

/// Streams `rays` through `trace` 64 at a time: the rays Embree may see are made into
/// records (`record`) and packed, `trace` runs over the packed records, and each ray's
/// answer is read from its record (`answer`); the others get `miss`.
fn stream<R: Copy + Default, T: Copy>(
    rays: &[Ray],
    out: &mut [T],
    miss: T,
    record: impl Fn(sys::RtcRay) -> R,
    trace: impl Fn(&mut [R]),
    answer: impl Fn(&R) -> T,
) {
    let mut buf = [R::default(); STREAM];
    for (rays, out) in rays.chunks(STREAM).zip(out.chunks_mut(STREAM)) {
        let mut m = 0;
        let mut slot = [0u8; STREAM];
        for (i, r) in rays.iter().enumerate() {
            out[i] = miss;
            if let Some(r) = rtc_ray(r) {
                buf[m] = record(r);
                slot[m] = i as u8;
                m += 1;
            }
        }
        if m > 0 {
            trace(&mut buf[..m]);
            for (r, &i) in buf[..m].iter().zip(&slot[..m]) {
                out[usize::from(i)] = answer(r);
            }
        }
    }
}

/// The context flag for a stream of coherent or incoherent rays.
fn context_flag(coherent: bool) -> i32 {
    if coherent {
        sys::CONTEXT_FLAG_COHERENT
    } else {
        sys::CONTEXT_FLAG_INCOHERENT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles of a unit square at z = 1.
    fn square() -> Scene {
        let v = [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        Scene::new(&v, &[[0, 1, 2], [0, 2, 3]], BuildQuality::High).expect("builds")
    }

    fn ray(x: f32, y: f32, t_max: f32) -> Ray {
        Ray {
            origin: [x, y, 0.0],
            dir: [0.0, 0.0, 1.0],
            t_max,
        }
    }

    #[test]
    fn single_and_stream_queries_agree_with_the_geometry() {
        let s = square();
        assert!(
            s.streams,
            "this Embree has no ray streams: the stream path is untested"
        );
        let h = s.intersect(&ray(0.75, 0.25, 5.0)).expect("hits");
        assert!((h.t - 1.0).abs() < 1e-6);
        assert_eq!(h.triangle, 0);
        // (1 - u - v) v0 + u v1 + v v2 = (0.75, 0.25): u = 0.5, v = 0.25.
        assert!((h.uv[0] - 0.5).abs() < 1e-5 && (h.uv[1] - 0.25).abs() < 1e-5);
        assert!(s.intersect(&ray(1.5, 0.5, 5.0)).is_none());
        assert!(s.occluded(&ray(0.25, 0.75, 2.0)));
        assert!(!s.occluded(&ray(0.25, 0.75, 0.5)));

        let rays: Vec<Ray> = (0..1000)
            // Off the edges and the diagonal, where either triangle is a right answer.
            .map(|i| {
                let (x, y) = (
                    (i % 40) as f32 / 20.0 - 0.4863,
                    (i / 40) as f32 / 20.0 + 0.0071,
                );
                ray(x, y, 0.5 + (i % 3) as f32)
            })
            .collect();
        for coherent in [false, true] {
            let mut occ = vec![true; rays.len()];
            s.occluded_many(&rays, coherent, &mut occ);
            let mut hits = vec![None; rays.len()];
            s.intersect_many(&rays, coherent, &mut hits);
            for (i, r) in rays.iter().enumerate() {
                assert_eq!(occ[i], s.occluded(r), "ray {i}");
                assert_eq!(hits[i], s.intersect(r), "ray {i}");
            }
        }
    }

    /// A filter that refuses the hits of triangle 0 where u > 0.25: rays there pass
    /// through to a second square behind (z = 2), singly and in streams, coherent or not,
    /// for closest hits and occlusion; rays elsewhere stop at the first square.
    #[test]
    fn a_filter_lets_rays_through_the_hits_it_refuses() {
        let v = [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
            [0.0, 0.0, 2.0],
            [1.0, 0.0, 2.0],
            [1.0, 1.0, 2.0],
            [0.0, 1.0, 2.0],
        ];
        let tris = [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
        let filter: HitFilter = std::sync::Arc::new(|t, [u, _]| t != 0 || u <= 0.25);
        let s = Scene::with_filter(&v, &tris, BuildQuality::High, Some(filter)).expect("builds");
        let mut rays = Vec::new();
        for i in 0..400 {
            let (x, y) = (
                (i % 20) as f32 / 20.0 + 0.0213,
                (i / 20) as f32 / 20.0 + 0.0171,
            );
            rays.push(ray(x, y, 1.5 + (i % 2) as f32));
        }
        for (i, r) in rays.iter().enumerate() {
            let (x, y) = (r.origin[0], r.origin[1]);
            // Triangle 0 holds x > y; its u at (x, y) is x - y.
            let through = x > y && x - y > 0.25;
            let h = s.intersect(r);
            let want_t = if through { 2.0 } else { 1.0 };
            let got_t = h.map(|h| h.t);
            if want_t < r.t_max {
                assert!(
                    (got_t.unwrap_or(0.0) - want_t).abs() < 1e-5,
                    "ray {i}: {h:?}"
                );
            } else {
                assert!(h.is_none(), "ray {i}: {h:?}");
            }
            assert_eq!(s.occluded(r), want_t < r.t_max, "ray {i}");
        }
        for coherent in [false, true] {
            let mut occ = vec![false; rays.len()];
            s.occluded_many(&rays, coherent, &mut occ);
            let mut hits = vec![None; rays.len()];
            s.intersect_many(&rays, coherent, &mut hits);
            for (i, r) in rays.iter().enumerate() {
                assert_eq!(occ[i], s.occluded(r), "ray {i}");
                assert_eq!(hits[i], s.intersect(r), "ray {i}");
            }
        }
    }

    #[test]
    fn bad_rays_hit_nothing_and_bad_meshes_are_refused() {
        let s = square();
        let nan = Ray {
            origin: [f32::NAN, 0.5, 0.0],
            ..ray(0.5, 0.5, 5.0)
        };
        assert!(!s.occluded(&nan) && s.intersect(&nan).is_none());
        let mut out = [true];
        s.occluded_many(&[nan], false, &mut out);
        assert!(!out[0]);
        let v = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, f32::INFINITY, 0.0]];
        assert!(matches!(
            Scene::new(&v, &[[0, 1, 2]], BuildQuality::Low),
            Err(Error::Mesh(_))
        ));
        assert!(matches!(
            Scene::new(&v[..2], &[[0, 1, 2]], BuildQuality::Low),
            Err(Error::Mesh(_))
        ));
        let empty = Scene::new(&[], &[], BuildQuality::Low).expect("an empty scene builds");
        assert!(empty.is_empty() && !empty.occluded(&ray(0.5, 0.5, 5.0)));
    }
}
