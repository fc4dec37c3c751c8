//! Issue 38, inputs: small files that promised huge work or memory, numbers that reached
//! shading unchecked, and count flags without a cap. Every case ends within seconds with
//! exit 0 and a right image or exit 2 and one line naming the cause; the runs that could
//! allocate go through an address-space limit of 8 GB. Each test failed before its fix.

use std::path::Path;
use std::process::{Command, Output};

use super::{assert_error, assert_ok, lgh, s, temp_dir};

/// `lgh ARGS` under `ulimit -v` of 8 GB.
fn lgh_limited(args: &[&str]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 8388608 && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_lgh"))
        .args(args)
        .env_remove("LGH_SCENES")
        .output()
        .unwrap()
}

fn render_limited(scene: &Path, out: &Path) -> Output {
    lgh_limited(&[
        "render",
        s(scene),
        "-o",
        s(out),
        "--size",
        "32x18",
        "--vpls",
        "100",
    ])
}

/// A PNG that claims `w` x `h` 8-bit RGB pixels, all zero: tiny when compressed.
fn png_bomb(path: &Path, w: u32, h: u32) {
    let mut bytes = Vec::new();
    let enc = image::codecs::png::PngEncoder::new_with_quality(
        &mut bytes,
        image::codecs::png::CompressionType::Best,
        image::codecs::png::FilterType::NoFilter,
    );
    use image::ImageEncoder;
    let zeros = vec![0u8; (w * h) as usize];
    enc.write_image(&zeros, w, h, image::ExtendedColorType::L8)
        .unwrap();
    std::fs::write(path, bytes).unwrap();
}

const QUAD: &str = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";

#[test]
fn texture_and_image_bombs_are_refused_before_decoding() {
    let d = temp_dir("bomb-texture");
    let out = d.join("o.png");
    // 9000 x 9000 (81M texels, over a texture's 64M): a few KB of PNG.
    png_bomb(&d.join("big.png"), 9000, 9000);
    std::fs::write(d.join("m.mtl"), "newmtl t\nKd 1 1 1\nmap_Kd big.png\n").unwrap();
    let obj = d.join("t.obj");
    std::fs::write(
        &obj,
        format!("mtllib m.mtl\n{QUAD}usemtl t\nf 1/1 3/3 2/2\n"),
    )
    .unwrap();
    assert_error(
        &render_limited(&obj, &out),
        &["big.png", "9000x9000 texels"],
    );
    // lgh diff of such an image: refused from its header.
    png_bomb(&d.join("wide.png"), 5000, 5000);
    let r = lgh_limited(&["diff", s(&d.join("wide.png")), s(&d.join("wide.png"))]);
    assert_error(&r, &["wide.png", "5000x5000", "at most"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn special_files_named_inside_scenes_are_refused() {
    let d = temp_dir("bomb-special");
    let out = d.join("o.png");
    // An MTL library that is /dev/zero: an error naming it (it never ends).
    let obj = d.join("z.obj");
    std::fs::write(&obj, format!("mtllib /dev/zero\n{QUAD}f 1 3 2\n")).unwrap();
    assert_error(&render_limited(&obj, &out), &["/dev/zero", "a device"]);
    // A scene file's mesh that is /dev/zero under an OBJ's name.
    let zero = d.join("zero.obj");
    let _ = std::fs::remove_file(&zero);
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let toml = d.join("z.toml");
    std::fs::write(&toml, "mesh = \"zero.obj\"\n").unwrap();
    assert_error(&render_limited(&toml, &out), &["zero.obj", "a device"]);
    // A glTF buffer that is /dev/zero.
    let gltf = d.join("z.gltf");
    std::fs::write(
        &gltf,
        r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"file:///dev/zero","byteLength":36}]}"#,
    )
    .unwrap();
    assert_error(&render_limited(&gltf, &out), &["/dev/zero", "a device"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_glb_that_instances_one_mesh_many_times_is_counted_first() {
    let d = temp_dir("bomb-instances");
    // One mesh of 20 000 triangles placed by 1000 nodes: refused from the accessors' counts,
    // before its buffer (which does not even exist) is read.
    let nodes: Vec<String> = (0..1000).map(|_| r#"{"mesh":0}"#.to_string()).collect();
    let roots: Vec<String> = (0..1000).map(|i| i.to_string()).collect();
    let text = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
        "buffers":[{{"uri":"none.bin","byteLength":720000}}],
        "bufferViews":[{{"buffer":0,"byteLength":720000}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":60000,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}}]}}"#,
        roots.join(","),
        nodes.join(",")
    );
    let p = d.join("many.gltf");
    std::fs::write(&p, text).unwrap();
    assert_error(
        &render_limited(&p, &d.join("o.png")),
        &["20000000 triangles", "more than"],
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn numbers_that_reach_shading_are_checked() {
    let d = temp_dir("bomb-numbers");
    let out = d.join("o.png");
    for (name, line) in [
        ("nan", "Kd nan 1 1"),
        ("neg", "Kd -1 1 1"),
        ("inf", "Ke inf 1 1"),
    ] {
        std::fs::write(d.join("m.mtl"), format!("newmtl bad\n{line}\n")).unwrap();
        let obj = d.join(format!("{name}.obj"));
        std::fs::write(&obj, format!("mtllib m.mtl\n{QUAD}usemtl bad\nf 1 3 2\n")).unwrap();
        assert_error(&render_limited(&obj, &out), &["material 'bad'", "finite"]);
    }
    // A keyframe moving an object by 1e23: refused at load (the BVH library panicked).
    std::fs::write(d.join("m.mtl"), "newmtl w\nKd 0.8 0.8 0.8\n").unwrap();
    std::fs::write(
        d.join("q.obj"),
        format!("mtllib m.mtl\no quad\n{QUAD}usemtl w\nf 1 3 2\n"),
    )
    .unwrap();
    let scene = |anim: &str| {
        let p = d.join("a.toml");
        std::fs::write(
            &p,
            format!(
                "mesh = \"q.obj\"\n[camera]\nposition = [0.0, 3.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 60.0\n\
                 [[lights]]\ntype = \"point\"\nposition = [0.0, 2.0, 0.0]\nintensity = [5.0, 5.0, 5.0]\n{anim}"
            ),
        )
        .unwrap();
        p
    };
    let far = scene(
        "[[animation.objects]]\nobject = \"quad\"\ntime = 0.0\ntranslation = [0.0, 0.0, 0.0]\n\
         [[animation.objects]]\nobject = \"quad\"\ntime = 0.05\ntranslation = [1e23, 0.0, 0.0]\n",
    );
    let frames = |p: &Path| {
        lgh_limited(&[
            "render",
            s(p),
            "-o",
            s(&d.join("f#.png")),
            "--size",
            "16x9",
            "--vpls",
            "50",
            "--frames",
            "0..3",
        ])
    };
    assert_error(&frames(&far), &["\"quad\"", "beyond 1e12"]);
    // Camera keyframes that pass through their look-at point: refused before frame 0.
    let cam = scene(
        "[[animation.camera]]\ntime = 0.0\nposition = [0.0, 0.0, 2.0]\nlook_at = [0.0, 0.0, -2.0]\n\
         [[animation.camera]]\ntime = 2.0\nposition = [0.0, 0.0, -2.0]\nlook_at = [0.0, 0.0, 2.0]\n",
    );
    let r = lgh_limited(&[
        "render",
        s(&cam),
        "-o",
        s(&d.join("c#.png")),
        "--size",
        "16x9",
        "--vpls",
        "50",
        "--frames",
        "0..48",
    ]);
    assert_error(&r, &["frame 24", "camera"]);
    assert!(
        !d.join("c0.png").exists(),
        "no frame is rendered before the check"
    );
    // Radiance past 1.8e19 stays white in a PNG, not black.
    let hot = d.join("hot.toml");
    std::fs::write(
        &hot,
        "mesh = \"q.obj\"\n[camera]\nposition = [0.0, 3.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 60.0\n\
         [[lights]]\ntype = \"point\"\nposition = [0.0, 0.5, 0.0]\nintensity = [1e30, 1e30, 1e30]\n",
    )
    .unwrap();
    let png = d.join("hot.png");
    assert_ok(&lgh(&[
        "render",
        s(&hot),
        "-o",
        s(&png),
        "--size",
        "16x9",
        "--vpls",
        "50",
    ]));
    let img = image::open(&png).unwrap().to_rgb8();
    assert!(
        img.pixels().any(|p| p.0 == [255, 255, 255]),
        "no saturated pixel"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn diff_refuses_bad_exposures_and_non_finite_images() {
    let d = temp_dir("bomb-diff");
    let (a, b) = (d.join("a.exr"), d.join("b.exr"));
    for (p, seed) in [(&a, "1"), (&b, "2")] {
        assert_ok(&lgh(&[
            "render",
            "-o",
            s(p),
            "--size",
            "16x9",
            "--vpls",
            "50",
            "--seed",
            seed,
        ]));
    }
    for bad in ["nan", "inf", "0", "-1"] {
        assert_error(
            &lgh(&["diff", s(&a), s(&b), &format!("--exposure={bad}")]),
            &["--exposure"],
        );
    }
    // An all-NaN EXR is not black: refused by name.
    let nan = d.join("nan.exr");
    exr::prelude::write_rgb_file(&nan, 16, 9, |_, _| (f32::NAN, f32::NAN, f32::NAN)).unwrap();
    assert_error(&lgh(&["diff", s(&nan), s(&b)]), &["nan.exr", "not finite"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn every_count_flag_has_a_stated_cap() {
    for args in [
        &["bench", "rays", "--rays", "100000000000"][..],
        &["bench", "build", "--lights", "99999999999"],
        &["bench", "render", "--vpls", "99999999999"],
        &["bench", "slc", "--vpls", "99999999999"],
        &["bench", "temporal", "--frames", "99999999"],
        &["bench", "quality", "--vpls", "99999999999"],
    ] {
        let r = lgh(args);
        assert_error(&r, &["is not in 1.."]);
    }
    assert_error(
        &lgh(&["render", "--area-samples", "100000"]),
        &["--area-samples 100000", "1024"],
    );
    assert_error(
        &lgh(&["render", "--bounces", "4000000000"]),
        &["--bounces 4000000000", "64"],
    );
    assert_error(
        &lgh(&["render", "--brute-rays", "70000"]),
        &["--brute-rays 70000", "65536"],
    );
    assert_error(&lgh(&["render", "--brute-rays", "0"]), &["--brute-rays 0"]);
    assert_error(
        &lgh(&["bench", "quality", "--reference-rays", "70000"]),
        &["--reference-rays", "70000"],
    );
    // The numbers of the benchmarks too.
    for args in [
        &["bench", "slc", "--error-bound=nan"][..],
        &["bench", "slc", "--pt-budget-ms=-1"],
        &["bench", "temporal", "--taa-alpha=inf"],
    ] {
        assert_error(&lgh(args), &[args[2].split('=').next().unwrap_or_default()]);
    }
}

#[test]
fn the_memory_check_honours_the_address_space_limit() {
    // 2M VPLs at 1280x720 need more than 1 GB: under `ulimit -v` of 1.5 GB the render is
    // refused before it allocates, naming the memory, instead of aborting.
    let d = temp_dir("bomb-memory");
    let out = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 1500000 && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_lgh"))
        .args(["render", "--size", "1280x720", "--vpls", "2000000", "-o"])
        .arg(d.join("o.png"))
        .output()
        .unwrap();
    assert_error(&out, &["available memory"]);
    let _ = std::fs::remove_dir_all(&d);
}
