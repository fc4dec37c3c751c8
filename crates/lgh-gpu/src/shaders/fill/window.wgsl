// The recombination window of a pixel under n x n interleaving (lgh-render's
// shading/interleave/fill.rs, Walks; LGH 2019 section 4.3, docs/design.md, "Filling cut
// windows"): the walks of the blur that recombines A (blur.wgsl with the crease bits), down
// and up its column, then along each row they reach. The kernels that include this declare
// `fp: FillParams`, `gbuffer` and `jumps`.

struct FillParams {
    width: u32,
    height: u32,
    // The recombination's walk length r (n / 2) and the interleaving n.
    radius: u32,
    n: u32,
    // A window reaching fewer sub-images than this fills the others (fill_below n^2).
    limit: f32,
    // The recombination's Gaussian sigma.
    sigma: f32,
    // vec4s per pixel of the images the recombination blurs (A is the first).
    planes: u32,
    _p0: u32,
}

fn hit(i: u32) -> bool {
    return gbuffer[i].position.w != 0.0;
}

// The steps of the recombination's walk from pixel i along y (`vertical`) or x, forwards or
// backwards, at most r: a step is allowed into a pixel of the image that sees a surface,
// across no jump of the pair (the crease bits: 4 along x, 8 along y), as blur.wgsl walks.
fn run(i: u32, vertical: bool, forward: bool) -> u32 {
    let w = fp.width;
    let pos = select(i % w, i / w, vertical);
    let len = select(w, fp.height, vertical);
    let step = select(1u, w, vertical);
    let bit = select(4u, 8u, vertical);
    var k = 0u;
    var at = i;
    if (forward) {
        while (k < fp.radius && pos + k + 1u < len) {
            let next = at + step;
            if ((jumps[at] & bit) != 0u || !hit(next)) {
                break;
            }
            k++;
            at = next;
        }
    } else {
        while (k < fp.radius && k < pos) {
            let next = at - step;
            if ((jumps[next] & bit) != 0u || !hit(next)) {
                break;
            }
            k++;
            at = next;
        }
    }
    return k;
}

// The sub-image of pixel i (lgh-render's sub_image_of): (y mod n) n + x mod n.
fn sub_image(i: u32) -> u32 {
    let n = fp.n;
    return ((i / fp.width) % n) * n + (i % fp.width) % n;
}
