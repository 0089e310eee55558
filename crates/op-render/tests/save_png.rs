//! `save_png` writes through no link planted where it writes: its
//! temporary file is created exclusively under a name no other process can
//! predict, then renamed over the picture.

use op_render::{save_png, RgbImage};

#[cfg(unix)]
#[test]
fn a_link_at_the_old_temporary_name_is_not_written_through() {
    let dir = std::env::temp_dir().join(format!("op-render-save-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let victim = dir.join("victim.txt");
    std::fs::write(&victim, "keep me").unwrap();
    // A predictable temporary name, `.<name>.tmp-<pid>`, planted as a link.
    let planted = dir.join(format!(".out.png.tmp-{}", std::process::id()));
    std::os::unix::fs::symlink(&victim, &planted).unwrap();
    let out = dir.join("out.png");
    save_png(&RgbImage::new(4, 3), &out).unwrap();
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep me");
    let picture = image::open(&out).unwrap();
    assert_eq!((picture.width(), picture.height()), (4, 3));
    let left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".opsim-tmp"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
