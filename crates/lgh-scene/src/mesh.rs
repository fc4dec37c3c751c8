//! One world-space triangle mesh, structure-of-arrays.

use glam::{Mat4, Vec2, Vec3};

/// All triangles of a scene in world space.
///
/// Vertices are shared through `triangles` (indices into the per-vertex arrays). A normal of
/// zero length means "none given": the face normal is used there (real files have such
/// vertices, e.g. Sponza's `vn 0 0 0`).
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Vertex normals (unit length, or zero for "use the face normal").
    pub normals: Vec<Vec3>,
    /// Vertex texture coordinates (zero when the file has none).
    pub uvs: Vec<Vec2>,
    /// Vertex colours (linear RGB in [0, 1]) that multiply the albedo (glTF `COLOR_0`, OBJ
    /// `v x y z r g b`): empty where no vertex has one, else one per vertex (white where
    /// its primitive has none).
    pub colors: Vec<Vec3>,
    /// Vertex indices of each triangle, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Material index of each triangle.
    pub materials: Vec<u32>,
    /// Object index of each triangle, into [`Mesh::object_names`]. An object is a named group
    /// of triangles (an OBJ `o`/`g` group, a glTF node) that an animation can move rigidly.
    pub objects: Vec<u32>,
    /// Names of the objects, indexed by [`Mesh::objects`].
    pub object_names: Vec<String>,
}

/// Vertex data of one primitive, before it is placed in the world.
#[derive(Clone, Debug, Default)]
pub struct Primitive {
    /// Object-space positions.
    pub positions: Vec<Vec3>,
    /// Object-space normals; empty if the file has none.
    pub normals: Vec<Vec3>,
    /// Texture coordinates; empty if the file has none.
    pub uvs: Vec<Vec2>,
    /// Vertex colours (linear RGB); empty if the file has none.
    pub colors: Vec<Vec3>,
    /// Triangle vertex indices into the arrays above.
    pub indices: Vec<[u32; 3]>,
    /// Material of every triangle.
    pub material: u32,
}

impl Mesh {
    /// Number of triangles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// True if there is no triangle.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The index of the object named `name`, added if new.
    pub fn object_id(&mut self, name: &str) -> u32 {
        match self.object_names.iter().position(|n| n == name) {
            Some(i) => i as u32,
            None => {
                self.object_names.push(name.to_string());
                self.object_names.len() as u32 - 1
            }
        }
    }

    /// Appends a primitive transformed by `to_world` as part of the object named `object`
    /// (primitives with the same object name move together); normals use the inverse
    /// transpose. Indices that point past the vertex arrays are dropped (the loaders validate
    /// first).
    pub fn append(&mut self, prim: &Primitive, to_world: Mat4, object: &str) {
        self.append_with(prim, to_world, object, |_| prim.material);
    }

    /// [`Mesh::append`] with the material of each of `prim`'s triangles (by its index in
    /// `prim.indices`) from `material_of`, in place of `prim.material`.
    pub fn append_with(
        &mut self,
        prim: &Primitive,
        to_world: Mat4,
        object: &str,
        material_of: impl Fn(usize) -> u32,
    ) {
        let object = self.object_id(object);
        let base = self.positions.len() as u32;
        let normal_m = to_world.inverse().transpose();
        let n = prim.positions.len();
        self.positions
            .extend(prim.positions.iter().map(|&p| to_world.transform_point3(p)));
        self.normals.extend((0..n).map(|i| {
            prim.normals
                .get(i)
                .map(|&v| normal_m.transform_vector3(v).normalize_or_zero())
                .unwrap_or(Vec3::ZERO)
        }));
        self.uvs
            .extend((0..n).map(|i| prim.uvs.get(i).copied().unwrap_or(Vec2::ZERO)));
        if !prim.colors.is_empty() || !self.colors.is_empty() {
            // Earlier vertices without colours are white; colours are kept within [0, 1].
            self.colors.resize(base as usize, Vec3::ONE);
            self.colors.extend((0..n).map(|i| {
                let c = prim.colors.get(i).copied().unwrap_or(Vec3::ONE);
                if c.is_finite() {
                    c.clamp(Vec3::ZERO, Vec3::ONE)
                } else {
                    Vec3::ONE
                }
            }));
        }
        for (k, t) in prim.indices.iter().enumerate() {
            if t.iter().all(|&i| (i as usize) < n) {
                self.triangles.push([t[0] + base, t[1] + base, t[2] + base]);
                self.materials.push(material_of(k));
                self.objects.push(object);
            }
        }
    }

    /// The three vertex positions of triangle `t`.
    #[inline]
    #[must_use]
    pub fn vertices(&self, t: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// The vertex colour of triangle `t` at barycentrics (b1, b2) (white without colours).
    #[inline]
    #[must_use]
    pub fn color_at(&self, t: usize, b: Vec2) -> Vec3 {
        if self.colors.is_empty() {
            return Vec3::ONE;
        }
        let [c0, c1, c2] =
            self.triangles[t].map(|i| self.colors.get(i as usize).copied().unwrap_or(Vec3::ONE));
        c0 * (1.0 - b.x - b.y) + c1 * b.x + c2 * b.y
    }

    /// Unnormalised face normal (v1 - v0) x (v2 - v0), twice the area in length.
    #[inline]
    #[must_use]
    pub fn face_cross(&self, t: usize) -> Vec3 {
        let [a, b, c] = self.vertices(t);
        (b - a).cross(c - a)
    }

    /// Area of triangle `t`.
    #[must_use]
    pub fn area(&self, t: usize) -> f32 {
        0.5 * self.face_cross(t).length()
    }

    /// Axis-aligned bounds (min, max) of the vertices used by triangles.
    #[must_use]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in 0..self.len() {
            for v in self.vertices(t) {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        (lo, hi)
    }

    /// Removes every triangle for which `keep` returns false.
    pub fn retain_triangles(&mut self, mut keep: impl FnMut(&Mesh, usize) -> bool) {
        let keep_flags: Vec<bool> = (0..self.len()).map(|t| keep(self, t)).collect();
        let mut k = keep_flags.iter();
        self.triangles.retain(|_| *k.next().unwrap_or(&false));
        let mut k = keep_flags.iter();
        self.materials.retain(|_| *k.next().unwrap_or(&false));
        let mut k = keep_flags.iter();
        self.objects.retain(|_| *k.next().unwrap_or(&false));
    }
}
