//! End-to-end tests of `op_render`: OBJ files written to a temp dir,
//! rendered in every style, saved and decoded again.
//!
//! Set `OPSIM_RENDER_EXAMPLES=/some/dir` to also keep one example PNG per style there.

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use op_render::{
    render, render_contact_sheet, render_data, render_obj_file, render_path, save_png, sheet_grid,
    CameraSpec, ObjData, RenderError, RenderOptions, RgbImage, Style,
};
use op_test_support::temp_dir;

/// A gently curved hexagonal patch of particles (positions and normals, no faces),
/// lifted by `lift` along `+y`.
fn hex_patch_obj(rings: i32, lift: f64) -> String {
    let mut s = String::from("o patch\n");
    let mut normals = String::new();
    let r0 = 0.1;
    for q in -rings..=rings {
        for r in -rings..=rings {
            if (q + r).abs() > rings {
                continue;
            }
            let x = r0 * (f64::from(q) + 0.5 * f64::from(r));
            let z = r0 * f64::from(r) * 3f64.sqrt() / 2.0;
            // y = 0.5 k (x^2 + z^2): normal (-k x, 1, -k z).
            let k = 0.8;
            let y = 0.5 * k * (x * x + z * z) + lift;
            writeln!(s, "v {x:.6} {y:.6} {z:.6}").unwrap();
            let len = (k * k * (x * x + z * z) + 1.0).sqrt();
            writeln!(
                normals,
                "vn {:.6} {:.6} {:.6}",
                -k * x / len,
                1.0 / len,
                -k * z / len
            )
            .unwrap();
        }
    }
    s + &normals
}

/// A UV sphere of radius `radius` at `center`, triangulated, normals per vertex.
fn sphere_obj(name: &str, center: [f64; 3], radius: f64, offset: usize) -> String {
    let (nu, nv) = (16, 10);
    let mut s = format!("o {name}\n");
    let mut verts = Vec::new();
    for j in 0..=nv {
        let th = PI * f64::from(j) / f64::from(nv);
        for i in 0..nu {
            let ph = 2.0 * PI * f64::from(i) / f64::from(nu);
            verts.push([th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()]);
        }
    }
    for v in &verts {
        let p: Vec<f64> = (0..3).map(|k| center[k] + radius * v[k]).collect();
        writeln!(s, "v {:.6} {:.6} {:.6}", p[0], p[1], p[2]).unwrap();
    }
    for v in &verts {
        writeln!(s, "vn {:.6} {:.6} {:.6}", v[0], v[1], v[2]).unwrap();
    }
    let id = |i: i32, j: i32| offset + (j * nu + i.rem_euclid(nu)) as usize + 1;
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}").unwrap();
            writeln!(s, "f {a}//{a} {c}//{c} {d}//{d}").unwrap();
        }
    }
    s
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn non_background(img: &RgbImage, bg: [u8; 3]) -> usize {
    img.pixels().filter(|p| p.0 != bg).count()
}

fn opts(style: Style, width: u32, height: u32) -> RenderOptions {
    RenderOptions {
        width,
        height,
        style,
        ..RenderOptions::default()
    }
}

fn count(img: &RgbImage, pred: impl Fn([u8; 3]) -> bool) -> usize {
    img.pixels().filter(|p| pred(p.0)).count()
}

#[test]
fn render_every_style_to_png_of_the_requested_size() {
    let dir = temp_dir("styles");
    let patch = write(&dir, "patch.obj", &hex_patch_obj(5, 0.0));
    let sphere = write(&dir, "sphere.obj", &sphere_obj("ball", [0.0; 3], 1.0, 0));
    let keep = std::env::var_os("OPSIM_RENDER_EXAMPLES").map(PathBuf::from);
    for style in Style::ALL {
        for (input, tag) in [(&patch, "patch"), (&sphere, "sphere")] {
            let o = opts(style, 320, 240);
            let img = render_obj_file(input, &o).unwrap();
            assert_eq!(img.dimensions(), (320, 240), "{style} {tag}");
            let inked = non_background(&img, o.background);
            assert!(
                inked > 320 * 240 / 50,
                "{style} {tag}: only {inked} pixels drawn"
            );
            assert!(
                inked < 320 * 240 * 9 / 10,
                "{style} {tag}: {inked} pixels drawn"
            );
            let png = dir.join(format!("{tag}_{style}.png"));
            save_png(&img, &png).unwrap();
            let back = image::open(&png).unwrap().to_rgb8();
            assert_eq!(back.dimensions(), (320, 240));
            assert_eq!(back, img, "PNG is lossless");
            if let Some(keep) = &keep {
                std::fs::create_dir_all(keep).unwrap();
                let big = render_obj_file(
                    input,
                    &RenderOptions {
                        style,
                        ..RenderOptions::default()
                    },
                )
                .unwrap();
                save_png(&big, &keep.join(format!("{tag}_{style}.png"))).unwrap();
            }
        }
    }
    // No temporary files left behind by the atomic writes.
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn render_styles_draw_what_they_say() {
    let patch = ObjData::parse(&hex_patch_obj(4, 0.0), "patch").unwrap();
    let sphere = ObjData::parse(&sphere_obj("ball", [0.0; 3], 1.0, 0), "sphere").unwrap();
    let (w, h) = (240, 180);

    // Axes: red, green and blue strokes.
    let axes = render_data(&patch, &opts(Style::Axes, w, h)).unwrap();
    assert!(count(&axes, |c| c[0] > 150 && c[1] < 110 && c[2] < 110) > 50);
    assert!(count(&axes, |c| c[1] > 110 && c[0] < 110 && c[2] < 110) > 50);
    assert!(count(&axes, |c| c[2] > 150 && c[0] < 110 && c[1] < 140) > 50);

    // Discs cover much more than the axes, and there is no note.
    let discs = render(&patch, &opts(Style::Discs, w, h)).unwrap();
    assert!(discs.notes.is_empty(), "{:?}", discs.notes);
    assert!(non_background(&discs.image, [255; 3]) > 2 * non_background(&axes, [255; 3]));

    // Shaded sphere: a filled silhouette; the centre is drawn.
    let shaded = render(&sphere, &opts(Style::Shaded, w, h)).unwrap();
    assert!(shaded.notes.is_empty(), "{:?}", shaded.notes);
    assert_ne!(shaded.image.get_pixel(w / 2, h / 2).0, [255; 3]);
    // Wireframe sphere: hidden-line removed edges, much of the inside stays background.
    let wire = render_data(&sphere, &opts(Style::Wireframe, w, h)).unwrap();
    let (s, wf) = (
        non_background(&shaded.image, [255; 3]),
        non_background(&wire, [255; 3]),
    );
    assert!(
        wf < s * 3 / 4 && wf > s / 10,
        "wireframe {wf} vs shaded {s}"
    );

    // Hidden lines are hidden: drawing the back faces' edges too would add pixels.
    // A sphere seen through (no faces, only its edges as lines) has more ink.
    let mut lines_only = String::new();
    for line in sphere_obj("ball", [0.0; 3], 1.0, 0).lines() {
        match line.strip_prefix("f ") {
            Some(rest) => {
                writeln!(lines_only, "l {rest} {}", rest.split(' ').next().unwrap()).unwrap()
            }
            None => writeln!(lines_only, "{line}").unwrap(),
        }
    }
    let see_through = ObjData::parse(&lines_only, "lines").unwrap();
    let st = render_data(&see_through, &opts(Style::Wireframe, w, h)).unwrap();
    assert!(non_background(&st, [255; 3]) > wf * 5 / 4);

    // Shaded and wireframe fall back to discs on particles, and say so.
    for style in [Style::Shaded, Style::Wireframe] {
        let r = render(&patch, &opts(style, w, h)).unwrap();
        assert!(
            r.notes.iter().any(|n| n.contains("discs")),
            "{style}: {:?}",
            r.notes
        );
        assert_eq!(
            r.image, discs.image,
            "{style} falls back to the discs picture"
        );
    }
}

#[test]
fn render_depth_does_not_depend_on_draw_order() {
    // Two facing triangles: a small near one at z = 1 inside a big far one at z = -1.
    let near = "o near\nv -0.5 -0.4 1\nv 0.5 -0.4 1\nv 0 0.5 1\n";
    let far = "o far\nv -2 -1.5 -1\nv 2 -1.5 -1\nv 0 2 -1\n";
    let faces = |first: usize| format!("f {} {} {}\n", first, first + 1, first + 2);
    let a = format!("{near}{}{far}{}", faces(1), faces(4)); // near is object 0
    let b = format!("{far}{}{near}{}", faces(1), faces(4)); // near is object 1
    let cam = CameraSpec {
        eye: [0.0, 0.0, 6.0],
        target: [0.0; 3],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 40.0,
    };
    let o = RenderOptions {
        width: 200,
        height: 200,
        style: Style::Shaded,
        camera: Some(cam),
        ..RenderOptions::default()
    };
    let ia = render_data(&ObjData::parse(&a, "a").unwrap(), &o).unwrap();
    let ib = render_data(&ObjData::parse(&b, "b").unwrap(), &o).unwrap();
    let centre = |i: &RgbImage| i.get_pixel(100, 100).0;
    // Inside the far triangle only (low on the picture, outside the near one).
    let far_only = |i: &RgbImage| i.get_pixel(100, 150).0;
    assert_ne!(centre(&ia), far_only(&ia), "two objects, two colours");
    assert_eq!(
        centre(&ia),
        far_only(&ib),
        "object 0's colour is on top in a"
    );
    assert_eq!(
        centre(&ib),
        far_only(&ia),
        "object 1's colour is on top in b"
    );

    // Eye between the two, looking at the far one: the near one is behind the eye
    // and must not show; a triangle through the eye plane is clipped, not smeared.
    let inside = RenderOptions {
        camera: Some(CameraSpec {
            eye: [0.0, 0.0, 0.0],
            target: [0.0, 0.0, -1.0],
            ..cam
        }),
        ..o.clone()
    };
    let ic = render_data(&ObjData::parse(&a, "a").unwrap(), &inside).unwrap();
    assert_eq!(
        centre(&ic),
        far_only(&ia),
        "the far triangle (object 1) fills the view"
    );
    assert!(
        !ic.pixels().any(|p| p.0 == centre(&ia)),
        "no pixel of the near triangle"
    );
    // A triangle through the eye plane, below the eye: clipped, drawn low only.
    let through = "o cross\nv -3 -3 2\nv 3 -3 2\nv 0 -0.2 -3\nf 1 2 3\n";
    let it = render_data(&ObjData::parse(through, "t").unwrap(), &inside).unwrap();
    assert_ne!(it.get_pixel(100, 190).0, [255; 3]);
    assert!((0..200).all(|x| it.get_pixel(x, 60).0 == [255; 3]));
}

#[test]
fn render_contact_sheet_of_five_frames() {
    let dir = temp_dir("sheet");
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    for k in 0..5 {
        let text = hex_patch_obj(3, 0.3 * f64::from(k));
        write(&frames, &format!("frame_{k:05}.obj"), &text);
    }
    write(&frames, "notes.txt", "not a frame");
    let (w, h) = (160u32, 120u32);
    let o = opts(Style::Discs, w, h);
    let sheet = render_contact_sheet(&dir, &o, 12).unwrap();
    assert_eq!(sheet_grid(5), (3, 2));
    assert_eq!(sheet.dimensions(), (3 * w, 2 * h));
    if let Some(keep) = std::env::var_os("OPSIM_RENDER_EXAMPLES").map(PathBuf::from) {
        std::fs::create_dir_all(&keep).unwrap();
        save_png(&sheet, &keep.join("contact_sheet_discs.png")).unwrap();
    }
    let cell = |c: u32| {
        let (x0, y0) = ((c % 3) * w, (c / 3) * h);
        image::imageops::crop_imm(&sheet, x0 + 1, y0 + 1, w - 1, h - 1).to_image()
    };
    // Every frame is drawn (more than its label) and moves up from frame to frame.
    let mut last_y = f64::INFINITY;
    for c in 0..5 {
        let img = cell(c);
        let coloured: Vec<(u32, u32)> = img
            .enumerate_pixels()
            .filter(|(_, _, p)| p.0 != [255; 3] && !(p.0[0] == p.0[1] && p.0[1] == p.0[2]))
            .map(|(x, y, _)| (x, y))
            .collect();
        assert!(coloured.len() > 200, "cell {c}: {}", coloured.len());
        let mean_y =
            coloured.iter().map(|&(_, y)| f64::from(y)).sum::<f64>() / coloured.len() as f64;
        assert!(mean_y < last_y - 3.0, "cell {c}: {mean_y} vs {last_y}");
        last_y = mean_y;
    }
    // The sixth cell is unused; its label corner is blank, the first cell's is inked.
    assert_eq!(non_background(&cell(5), [255; 3]), 0);
    assert!(
        non_background(
            &image::imageops::crop_imm(&cell(0), 0, 0, 16, 20).to_image(),
            [255; 3]
        ) > 10
    );

    // Fewer frames than files: first and last kept.
    let two = render_contact_sheet(&frames, &o, 2).unwrap();
    assert_eq!(two.dimensions(), (2 * w, h));
    // render_path picks the sheet for a directory and a single picture for a file.
    let r = render_path(&dir, &o, 4).unwrap();
    assert_eq!(r.image.dimensions(), (2 * w, 2 * h));
    let r = render_path(&frames.join("frame_00000.obj"), &o, 4).unwrap();
    assert_eq!(r.image.dimensions(), (w, h));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn render_bad_inputs_are_errors() {
    let dir = temp_dir("bad");
    let o = RenderOptions::default();
    let missing = dir.join("missing.obj");
    let e = render_obj_file(&missing, &o).unwrap_err();
    assert!(
        matches!(&e, RenderError::Io { path, .. } if path == &missing),
        "{e:?}"
    );
    assert!(e.to_string().contains("missing.obj"), "{e}");

    let e = render_contact_sheet(&dir, &o, 9).unwrap_err();
    assert!(matches!(e, RenderError::Empty { .. }), "{e:?}");
    assert!(e.to_string().contains("no .obj files"), "{e}");
    let e = render_contact_sheet(&dir.join("nope"), &o, 9).unwrap_err();
    assert!(matches!(e, RenderError::Io { .. }), "{e:?}");

    let good = write(&dir, "ok.obj", &hex_patch_obj(2, 0.0));
    for (w, h, what) in [
        (0, 600, "width"),
        (800, 0, "height"),
        (100_000, 10, "width"),
    ] {
        let bad = RenderOptions {
            width: w,
            height: h,
            ..RenderOptions::default()
        };
        let e = render_obj_file(&good, &bad).unwrap_err();
        assert!(
            matches!(e, RenderError::BadOption { option, .. } if option == what),
            "{e:?}"
        );
        assert!(e.to_string().contains("allowed"), "{e}");
    }
    let e = render_contact_sheet(&dir, &o, 0).unwrap_err();
    assert!(matches!(e, RenderError::BadOption { .. }), "{e:?}");
    let bad_cam = RenderOptions {
        camera: Some(CameraSpec {
            eye: [0.0; 3],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 30.0,
        }),
        ..RenderOptions::default()
    };
    assert!(matches!(
        render_obj_file(&good, &bad_cam),
        Err(RenderError::BadOption { .. })
    ));

    let empty = write(&dir, "empty.obj", "# nothing\no nothing\n");
    let e = render_obj_file(&empty, &o).unwrap_err();
    assert!(matches!(e, RenderError::Empty { .. }), "{e:?}");
    assert!(e.to_string().contains("empty.obj"), "{e}");

    let broken = write(&dir, "broken.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    let e = render_obj_file(&broken, &o).unwrap_err();
    match &e {
        RenderError::Parse {
            file,
            line,
            message,
        } => {
            assert!(file.ends_with("broken.obj"), "{file}");
            assert_eq!(*line, 4);
            assert!(message.contains("out of range"), "{message}");
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
    // A broken frame in a directory is reported too.
    let e = render_contact_sheet(&dir, &o, 9).unwrap_err();
    assert!(matches!(e, RenderError::Parse { .. }), "{e:?}");

    let img = RgbImage::new(4, 4);
    let e = save_png(&img, &dir.join("no/such/dir/out.png")).unwrap_err();
    assert!(matches!(e, RenderError::Io { .. }), "{e:?}");
    let e = save_png(&img, Path::new("/")).unwrap_err();
    assert!(matches!(e, RenderError::BadOption { .. }), "{e:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
