//! The alpha test every ray makes, gathered for the tracers: which triangles have a cut-out
//! ([`crate::material::Cutout`]) and their corners' texture coordinates, so that a hit at
//! barycentrics (b1, b2) is tested without the scene (docs/design.md, "Alpha cut-outs").
//! The CPU's tracers (obvhs and Embree) call [`Cutouts::covers`]; the GPU's traversal reads
//! the same records from its triangle buffer.

use glam::Vec2;

use crate::material::Cutout;
use crate::{Scene, Texture};

/// No record: the triangle is opaque.
const OPAQUE: u32 = u32::MAX;

/// The cut-out triangles of a scene and what their alpha test reads.
#[derive(Clone, Debug)]
pub struct Cutouts {
    /// Per triangle of the mesh, its record's index, or [`OPAQUE`].
    record: Vec<u32>,
    /// Per record: its triangle's corners' texture coordinates, as the cut-out maps them.
    corners: Vec<[Vec2; 3]>,
    /// Per record: its cut-out's index in `cutouts`.
    cutout_of: Vec<u32>,
    /// The distinct cut-outs, their textures re-indexed into `textures`.
    cutouts: Vec<Cutout>,
    /// The alpha of the textures the cut-outs read (their colour left out: empty texels).
    textures: Vec<Texture>,
}

impl Cutouts {
    /// The cut-outs of `scene`'s triangles, or `None` if every triangle is opaque.
    #[must_use]
    pub fn of(scene: &Scene) -> Option<Self> {
        let mut of_material = vec![OPAQUE; scene.materials.len()];
        let mut cutouts = Vec::new();
        let mut textures = Vec::new();
        let mut texture_index = std::collections::HashMap::new();
        for (m, material) in scene.materials.iter().enumerate() {
            let Some(mut c) = material.cutout else {
                continue;
            };
            c.texture = c.texture.and_then(|t| {
                let texture = scene.textures.get(t as usize)?;
                Some(*texture_index.entry(t).or_insert_with(|| {
                    textures.push(Texture {
                        texels: Vec::new(),
                        alpha: texture.alpha.clone(),
                        ..*texture
                    });
                    textures.len() as u32 - 1
                }))
            });
            of_material[m] = cutouts.len() as u32;
            cutouts.push(c);
        }
        if cutouts.is_empty() {
            return None;
        }
        let mesh = &scene.mesh;
        let mut record = vec![OPAQUE; mesh.len()];
        let mut corners = Vec::new();
        let mut cutout_of = Vec::new();
        for (t, (tri, &m)) in mesh.triangles.iter().zip(&mesh.materials).enumerate() {
            let Some(&c) = of_material.get(m as usize).filter(|&&c| c != OPAQUE) else {
                continue;
            };
            let cut = &cutouts[c as usize];
            record[t] = corners.len() as u32;
            corners.push(tri.map(|v| {
                let uv = mesh.uvs.get(v as usize).copied().unwrap_or(Vec2::ZERO);
                uv * cut.scale + cut.offset
            }));
            cutout_of.push(c);
        }
        if corners.is_empty() {
            return None;
        }
        // The corners are mapped already.
        for c in &mut cutouts {
            c.scale = Vec2::ONE;
            c.offset = Vec2::ZERO;
        }
        Some(Self {
            record,
            corners,
            cutout_of,
            cutouts,
            textures,
        })
    }

    /// True if triangle `triangle` is there at barycentrics `b` = (b1, b2) (the point
    /// (1 - b1 - b2) v0 + b1 v1 + b2 v2): a hit there counts. Opaque triangles always are.
    #[inline]
    #[must_use]
    pub fn covers(&self, triangle: u32, b: Vec2) -> bool {
        match self.triangle(triangle) {
            None => true,
            Some((corners, cut)) => {
                let uv = corners[0] * (1.0 - b.x - b.y) + corners[1] * b.x + corners[2] * b.y;
                self.cutouts[cut].covers(&self.textures, uv)
            }
        }
    }

    /// The corners' texture coordinates of triangle `triangle` and the index of its
    /// cut-out in [`Cutouts::cutouts`], if it has one.
    #[inline]
    #[must_use]
    pub fn triangle(&self, triangle: u32) -> Option<(&[Vec2; 3], usize)> {
        let r = *self.record.get(triangle as usize)?;
        if r == OPAQUE {
            return None;
        }
        let corners = self.corners.get(r as usize)?;
        Some((corners, *self.cutout_of.get(r as usize)? as usize))
    }

    /// The distinct cut-outs (their textures index [`Cutouts::textures`]).
    #[must_use]
    pub fn cutouts(&self) -> &[Cutout] {
        &self.cutouts
    }

    /// The textures the cut-outs read: their alpha alone ([`Texture::alpha_at`]), no
    /// colour.
    #[must_use]
    pub fn textures(&self) -> &[Texture] {
        &self.textures
    }

    /// Number of triangles with a cut-out.
    #[must_use]
    pub fn len(&self) -> usize {
        self.corners.len()
    }

    /// True if no triangle has a cut-out (never, for a value [`Cutouts::of`] made).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.corners.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::gltf;
    use crate::texture::Wrap;

    const TEXTURED: &str = r#""pbrMetallicRoughness":{"baseColorTexture":{"index":0}}"#;

    /// Whether the triangle is there at texture coordinates (u, 0.1), which are its
    /// barycentrics (b1, b2) (its coordinates equal x and y).
    fn covered(c: &Cutouts, u: f32) -> bool {
        c.covers(0, Vec2::new(u, 0.1))
    }

    /// MASK cuts where the texture's alpha (times the factor) is below alphaCutoff: the
    /// clamped 2 x 1 texture's alpha rises from 0 at u = 0.25 to 200/255 at u = 0.75.
    #[test]
    fn gltf_mask_cuts_below_its_cutoff() {
        let s = gltf(&format!(r#"{{"alphaMode":"MASK",{TEXTURED}}}"#));
        let cut = s.materials[0].cutout.expect("a cut-out");
        assert_eq!((cut.texture, cut.cutoff, cut.factor), (Some(0), 0.5, 1.0));
        assert_eq!(cut.wrap, [Wrap::Clamp; 2]);
        let c = Cutouts::of(&s).expect("cut-outs");
        // alpha(u) = (u - 0.25) / 0.5 x 200/255 = 0.5 at u = 0.569.
        for (u, want) in [
            (0.1, false),
            (0.5, false),
            (0.55, false),
            (0.6, true),
            (0.9, true),
        ] {
            assert_eq!(covered(&c, u), want, "u {u}");
        }
        // A higher cutoff and a factor of one half move the edge; 0.4 is never reached.
        let s = gltf(
            r#"{"alphaMode":"MASK","alphaCutoff":0.3,"pbrMetallicRoughness":{"baseColorFactor":[1,1,1,0.5],"baseColorTexture":{"index":0}}}"#,
        );
        let c = Cutouts::of(&s).expect("cut-outs");
        // 0.5 x alpha(u) >= 0.3: u >= 0.25 + 0.6 x 255/200 x 0.5 = 0.6325.
        for (u, want) in [(0.6, false), (0.62, false), (0.65, true), (0.9, true)] {
            assert_eq!(covered(&c, u), want, "u {u}");
        }
    }

    /// OPAQUE ignores the texture's alpha; BLEND of a varying alpha cuts at 0.5; MASK
    /// without a texture cuts the whole material where the factor is below the cutoff;
    /// BLEND of a uniform alpha (glass) stays opaque with a warning.
    #[test]
    fn gltf_alpha_modes() {
        let s = gltf(&format!(r#"{{{TEXTURED}}}"#));
        assert_eq!(s.materials[0].cutout, None);
        assert!(Cutouts::of(&s).is_none());
        let s = gltf(&format!(r#"{{"alphaMode":"BLEND",{TEXTURED}}}"#));
        assert_eq!(s.materials[0].cutout.map(|c| c.cutoff), Some(0.5));
        let s =
            gltf(r#"{"alphaMode":"MASK","pbrMetallicRoughness":{"baseColorFactor":[1,1,1,0.2]}}"#);
        let c = Cutouts::of(&s).expect("cut-outs");
        assert!(!covered(&c, 0.1) && !covered(&c, 0.9));
        let s = gltf(
            r#"{"name":"glass","alphaMode":"BLEND","pbrMetallicRoughness":{"baseColorFactor":[1,1,1,0.2]}}"#,
        );
        assert_eq!(s.materials[0].cutout, None);
        let w = &s.report.warnings;
        assert!(
            w.iter()
                .any(|w| w.contains("'glass'") && w.contains("opaque")),
            "{w:?}"
        );
    }

    /// A `map_d` whose file is missing leaves the surface opaque, and the warning says so.
    #[test]
    fn a_missing_mask_is_a_warning_and_no_cut_out() {
        let d = std::env::temp_dir().join(format!("lgh-missing-mask-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join("m.mtl"), "newmtl a\nmap_d gone.png\n").unwrap();
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
        std::fs::write(d.join("s.obj"), obj).unwrap();
        let scene = crate::obj::load(&d.join("s.obj")).unwrap();
        let _ = std::fs::remove_dir_all(&d);
        assert_eq!(scene.materials[0].cutout, None);
        let w = &scene.report.warnings;
        assert!(
            w.iter()
                .any(|w| w.contains("gone.png") && w.contains("no cut-out")),
            "{w:?}"
        );
    }

    /// The project's lattice scene (OBJ `map_d` of an RGBA PNG, one with `-s 2 2`): its
    /// screens are cut where the texture's alpha is 0, the standing one at twice the
    /// frequency, and its floor and walls are opaque.
    #[test]
    fn the_lattice_scene_has_its_holes() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/test/lattice.toml");
        let scene = crate::load(&path).unwrap();
        let c = Cutouts::of(&scene).expect("cut-outs");
        assert_eq!(c.len(), 6);
        let by_name = |n: &str| scene.materials.iter().find(|m| m.name == n).unwrap();
        assert_eq!(by_name("floor").cutout, None);
        let level = by_name("screen").cutout.expect("cut");
        let standing = by_name("standing").cutout.expect("cut");
        assert_eq!(level.scale, Vec2::ONE);
        assert_eq!(standing.scale, Vec2::splat(2.0));
        let tex = &scene.textures[level.texture.unwrap() as usize];
        // The tile's bars: u (and v from the top) in the first quarter of the tile.
        let v_top = |t: f32| 1.0 - t;
        for (uv, want) in [
            (Vec2::new(0.1, v_top(0.5)), true),
            (Vec2::new(0.5, v_top(0.1)), true),
            (Vec2::new(0.6, v_top(0.6)), false),
            (Vec2::new(1.6, v_top(0.6)), false),
        ] {
            assert_eq!(level.covers(&scene.textures, uv), want, "{uv}");
            assert!(tex.has_alpha());
        }
        // The standing screen at half the coordinates reads the same texels.
        assert!(!standing.covers(&scene.textures, Vec2::new(0.3, 0.2)));
        assert!(standing.covers(&scene.textures, Vec2::new(0.05, 0.2)));
    }
}
