//! Tangent-space normal maps (glTF `normalTexture`): the shading normal bent by a texture,
//! in a tangent frame computed per triangle from its positions and texture coordinates
//! (docs/design.md, "Normal maps"). lgh-render's `World::surface` and the GPU's
//! `surface.wgsl` both call this arithmetic.

use glam::{Vec2, Vec3};

use crate::texture::{Texture, Wrap};

/// A tangent-space normal map: the texel t (a data texture, [`Texture::linear`]) gives the
/// normal ((2 t - 1), x and y times `scale`) in the frame of the surface's tangent (the
/// direction of increasing u), bitangent (increasing v, up the image) and shading normal;
/// read at the mesh's texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalMap {
    /// Index into [`crate::Scene::textures`].
    pub texture: u32,
    /// How the texture reads beyond [0, 1].
    pub wrap: [Wrap; 2],
    /// glTF's `scale` of the normal's x and y.
    pub scale: f32,
}

impl NormalMap {
    /// The shading normal `n` (unit, on the side the ray came from, as is the geometric
    /// normal `geo`) bent by the map at `uv` on the triangle of corners `p` and texture
    /// coordinates `t`: `n` itself where the texture is missing, the triangle's coordinates
    /// are degenerate or the bent normal is not on `geo`'s side.
    #[must_use]
    pub fn bend(
        &self,
        textures: &[Texture],
        uv: Vec2,
        n: Vec3,
        geo: Vec3,
        p: [Vec3; 3],
        t: [Vec2; 3],
    ) -> Vec3 {
        let Some(tex) = textures.get(self.texture as usize) else {
            return n;
        };
        let m = tex.sample_wrapped(uv, self.wrap) * 2.0 - Vec3::ONE;
        bend(
            n,
            geo,
            p,
            t,
            Vec3::new(m.x * self.scale, m.y * self.scale, m.z),
        )
    }
}

/// `n` bent to the tangent-space normal `m` (x along the tangent, y the bitangent, z `n`),
/// the frame from the triangle's positions `p` and texture coordinates `t`: the tangent is
/// dp/du and the bitangent dp/dv, each made orthogonal to `n` (and the bitangent to the
/// tangent), so that a mirrored mapping keeps its handedness.
#[must_use]
pub fn bend(n: Vec3, geo: Vec3, p: [Vec3; 3], t: [Vec2; 3], m: Vec3) -> Vec3 {
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
    let det = d1.x * d2.y - d1.y * d2.x;
    if det == 0.0 || !det.is_finite() {
        return n;
    }
    let dpdu = (e1 * d2.y - e2 * d1.y) / det;
    let dpdv = (e2 * d1.x - e1 * d2.x) / det;
    let tangent = (dpdu - n * n.dot(dpdu)).normalize_or_zero();
    let b = dpdv - n * n.dot(dpdv);
    let bitangent = (b - tangent * tangent.dot(b)).normalize_or_zero();
    let bent = (tangent * m.x + bitangent * m.y + n * m.z).normalize_or_zero();
    if tangent == Vec3::ZERO || bitangent == Vec3::ZERO || bent.dot(geo) <= 0.0 {
        n
    } else {
        bent
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::gltf;

    /// A glTF `normalTexture` on the base colour's set is read with its scale, as data:
    /// the image is converted in place when no material reads it as colour, and copied
    /// when one does (its colour texture keeps the sRGB decoding); on another set it is a
    /// warning.
    #[test]
    fn gltf_normal_textures_are_read_as_data() {
        let s = gltf(r#"{"normalTexture":{"index":0,"scale":0.5}}"#);
        let map = s.materials[0].normal_map.expect("a normal map");
        assert_eq!((map.texture, map.scale), (0, 0.5));
        assert_eq!(s.textures.len(), 1);
        let t = &s.textures[0];
        assert!(t.linear);
        // The first texel's 255 reads 1 either way; a code of 128 would read 0.502.
        assert_eq!(t.texels[0], Vec3::ONE);
        let s = gltf(
            r#"{"normalTexture":{"index":0},"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}"#,
        );
        let m = &s.materials[0];
        let map = m.normal_map.expect("a normal map");
        assert_eq!(s.textures.len(), 2);
        assert_eq!((m.albedo_texture, map.texture), (Some(0), 1));
        assert!(!s.textures[0].linear && s.textures[1].linear);
        let s = gltf(r#"{"normalTexture":{"index":0,"texCoord":1}}"#);
        assert_eq!(s.materials[0].normal_map, None);
        let w = &s.report.warnings;
        assert!(w.iter().any(|w| w.contains("normal map")), "{w:?}");
    }

    /// An sRGB texture's codes come back exactly, and read as data they are code / 255.
    #[test]
    fn a_colour_texture_reads_as_data_through_its_codes() {
        let bytes = [0u8, 1, 127, 128, 200, 255];
        let c = Texture::from_srgb8(2, 1, 3, &bytes).unwrap();
        let codes = c.codes();
        assert_eq!(codes, vec![0, 1, 127, 255, 128, 200, 255, 255]);
        let d = c.as_linear();
        assert!(d.linear);
        assert_eq!(d.texels[1], Vec3::new(128.0, 200.0, 255.0) / 255.0);
    }

    /// A square in the xz plane facing up (+y), u along +x and v along -z: a map normal
    /// tilted along +x (tangent-space (sin a, 0, cos a)) bends the normal towards +x, one
    /// tilted along +y (the bitangent) towards -z; the same on the mirrored mapping (u
    /// along -x) bends towards -x; a flat map (0, 0, 1) leaves it; a map normal facing
    /// down leaves it.
    #[test]
    fn the_frame_follows_the_texture_coordinates() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 0.0, -1.0)];
        let t = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let (n, a) = (Vec3::Y, 0.3f32);
        let got = bend(n, n, p, t, Vec3::new(a.sin(), 0.0, a.cos()));
        assert!(
            (got - Vec3::new(a.sin(), a.cos(), 0.0)).length() < 1e-5,
            "{got}"
        );
        let got = bend(n, n, p, t, Vec3::new(0.0, a.sin(), a.cos()));
        assert!(
            (got - Vec3::new(0.0, a.cos(), -a.sin())).length() < 1e-5,
            "{got}"
        );
        let mirrored = [Vec2::ZERO, -Vec2::X, Vec2::Y];
        let got = bend(n, n, p, mirrored, Vec3::new(a.sin(), 0.0, a.cos()));
        assert!(
            (got - Vec3::new(-a.sin(), a.cos(), 0.0)).length() < 1e-5,
            "{got}"
        );
        assert!((bend(n, n, p, t, Vec3::Z) - n).length() < 1e-6);
        assert_eq!(bend(n, n, p, t, Vec3::new(0.0, 0.0, -1.0)), n);
        // Degenerate coordinates: the normal as it was.
        assert_eq!(bend(n, n, p, [Vec2::ZERO; 3], Vec3::X), n);
    }

    /// Through a texture: a constant texel (128 + 127 sin a, 128, 128 + 127 cos a) / 255
    /// at scale 1 and 0.5.
    #[test]
    fn a_constant_map_tilts_by_its_texel() {
        let a = 0.5f32;
        let [r, b] = [a.sin(), a.cos()].map(|x| (127.5 + 127.5 * x).round() as u8);
        let tex = Texture::from_linear8(1, 1, 3, &[r, 128, b]).unwrap();
        let m = tex.texels[0] * 2.0 - Vec3::ONE;
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 0.0, -1.0)];
        let t = [Vec2::ZERO, Vec2::X, Vec2::Y];
        for scale in [1.0f32, 0.5] {
            let map = NormalMap {
                texture: 0,
                wrap: [Wrap::Repeat; 2],
                scale,
            };
            let got = map.bend(
                std::slice::from_ref(&tex),
                Vec2::splat(0.3),
                Vec3::Y,
                Vec3::Y,
                p,
                t,
            );
            let want = Vec3::new(m.x * scale, m.z, -m.y * scale).normalize();
            assert!(
                (got - want).length() < 1e-5,
                "{scale}: {got} against {want}"
            );
        }
        // A missing texture: unchanged.
        let map = NormalMap {
            texture: 3,
            wrap: [Wrap::Repeat; 2],
            scale: 1.0,
        };
        assert_eq!(map.bend(&[], Vec2::ZERO, Vec3::Y, Vec3::Y, p, t), Vec3::Y);
    }
}
