//! Recording discovery and frame loading (PNG/TIFF, 8/16 bit, file-name order), and every bad-input case: one-line errors naming the file, never a panic.

use image::{GrayImage, ImageBuffer, ImageFormat, Luma};
use rbc_analysis::experiment::recording::{detect_recording, discover, Recording};
use rbc_analysis::simulated::synth::{random_spec, write_recording};
use std::path::Path;

const TOML: &str = "fps = 400.0\num_per_px = 0.2\npressure_mbar = 100.0\nposition_mm = 10.0\n";

fn toml(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("recording.toml"), TOML).unwrap();
}

/// An 8-bit frame whose pixel (0, 0) holds `v` and the rest 100.
fn png8(path: &Path, v: u8, w: u32, h: u32) {
    let mut img = GrayImage::from_pixel(w, h, Luma([100]));
    img.put_pixel(0, 0, Luma([v]));
    img.save_with_format(path, ImageFormat::Png).unwrap();
}

fn frame16(path: &Path, v: u16, fmt: ImageFormat) {
    let mut img: ImageBuffer<Luma<u16>, Vec<u16>> = ImageBuffer::from_pixel(16, 12, Luma([1000]));
    img.put_pixel(0, 0, Luma([v]));
    img.save_with_format(path, fmt).unwrap();
}

/// The error message of a failed call: one line, naming `needle`.
fn one_line_naming<T: std::fmt::Debug>(r: Result<T, rbc_analysis::AnalysisError>, needle: &str) -> String {
    let msg = r.expect_err("expected an error").to_string();
    assert!(msg.contains(needle), "error does not name {needle:?}: {msg}");
    assert!(!msg.contains('\n'), "not one line: {msg}");
    msg
}

#[test]
fn frames_load_in_file_name_order_8_bit_png() {
    let d = tempfile::tempdir().unwrap();
    toml(d.path());
    // written out of order; file-name order is f_0 < f_1 < f_10 < f_2
    for (name, v) in [("f_2.png", 4u8), ("f_10.png", 3), ("f_0.png", 1), ("f_1.png", 2)] {
        png8(&d.path().join(name), v, 16, 12);
    }
    std::fs::write(d.path().join("notes.txt"), "ignored").unwrap();
    let rec = Recording::open(d.path()).unwrap();
    assert_eq!((rec.width, rec.height, rec.n_frames()), (16, 12, 4));
    let frames = rec.load_frames().unwrap();
    let first: Vec<f32> = frames.iter().map(|f| f.at(0, 0) * 255.0).collect();
    assert_eq!(first, vec![1.0, 2.0, 3.0, 4.0]);
    assert!((frames[0].at(3, 3) - 100.0 / 255.0).abs() < 1e-7);
    assert_eq!(rec.time_s(2), 2.0 / 400.0);
}

#[test]
fn sixteen_bit_png_and_tiff_and_eight_bit_tiff_scale_to_unit_range() {
    for (fmt, ext) in [(ImageFormat::Png, "png"), (ImageFormat::Tiff, "tif"), (ImageFormat::Tiff, "tiff")] {
        let d = tempfile::tempdir().unwrap();
        toml(d.path());
        frame16(&d.path().join(format!("a.{ext}")), 65535, fmt);
        frame16(&d.path().join(format!("b.{ext}")), 13107, fmt);
        let f = Recording::open(d.path()).unwrap().load_frames().unwrap();
        assert_eq!(f[0].at(0, 0), 1.0);
        assert!((f[1].at(0, 0) - 0.2).abs() < 1e-6, "{ext}");
        assert!((f[1].at(5, 5) - 1000.0 / 65535.0).abs() < 1e-7);
    }
    let d = tempfile::tempdir().unwrap();
    toml(d.path());
    let mut img = GrayImage::from_pixel(16, 12, Luma([0]));
    img.put_pixel(0, 0, Luma([51]));
    img.save_with_format(d.path().join("a.tif"), ImageFormat::Tiff).unwrap();
    let f = Recording::open(d.path()).unwrap().load_frame(0).unwrap();
    assert!((f.at(0, 0) - 0.2).abs() < 1e-7);
}

#[test]
fn recordings_are_found_recursively_and_sorted() {
    let root = tempfile::tempdir().unwrap();
    for sub in ["b/deep/r2", "a/r1", ".hidden/r3"] {
        let d = root.path().join(sub);
        toml(&d);
        png8(&d.join("f.png"), 0, 16, 12);
    }
    std::fs::create_dir_all(root.path().join("empty")).unwrap();
    let found = discover(root.path()).unwrap();
    assert_eq!(found, vec![root.path().join("a/r1"), root.path().join("b/deep/r2")]);
    let rec = Recording::open_under(root.path(), &found[1]).unwrap();
    assert_eq!(rec.name, "b/deep/r2");
    // a recording folder given directly is itself the only recording
    assert_eq!(discover(&found[0]).unwrap(), vec![found[0].clone()]);
}

#[test]
fn empty_or_missing_folder() {
    let d = tempfile::tempdir().unwrap();
    one_line_naming(discover(d.path()), &d.path().display().to_string());
    one_line_naming(discover(&d.path().join("nope")), "nope");
    // recording.toml but no frame
    toml(d.path());
    one_line_naming(Recording::open(d.path()), "no frames");
}

#[test]
fn missing_or_invalid_recording_toml_names_file_and_field() {
    let d = tempfile::tempdir().unwrap();
    png8(&d.path().join("f.png"), 0, 16, 12);
    one_line_naming(Recording::open(d.path()), "recording.toml");
    std::fs::write(d.path().join("recording.toml"), TOML.replace("fps = 400.0", "fps = -4")).unwrap();
    let m = one_line_naming(Recording::open(d.path()), "recording.toml");
    assert!(m.contains("fps"), "{m}");
    std::fs::write(d.path().join("recording.toml"), TOML.replace("um_per_px = 0.2\n", "")).unwrap();
    let m = one_line_naming(Recording::open(d.path()), "recording.toml");
    assert!(m.contains("um_per_px"), "{m}");
    std::fs::write(d.path().join("recording.toml"), "fps = [\n").unwrap();
    one_line_naming(Recording::open(d.path()), "recording.toml");
}

#[test]
fn unreadable_and_truncated_images_name_the_file() {
    let d = tempfile::tempdir().unwrap();
    toml(d.path());
    png8(&d.path().join("f_0.png"), 0, 64, 48);
    std::fs::write(d.path().join("f_1.png"), b"this is not a png").unwrap();
    one_line_naming(Recording::open(d.path()), "f_1.png");
    // truncated: valid header, half of the data
    let full = std::fs::read(d.path().join("f_0.png")).unwrap();
    let mut noisy = GrayImage::new(64, 48);
    for (i, p) in noisy.pixels_mut().enumerate() {
        *p = Luma([(i * 7919 % 251) as u8]);
    }
    noisy.save_with_format(d.path().join("f_1.png"), ImageFormat::Png).unwrap();
    let bytes = std::fs::read(d.path().join("f_1.png")).unwrap();
    std::fs::write(d.path().join("f_1.png"), &bytes[..bytes.len() / 2]).unwrap();
    assert!(full.len() > 8);
    // channel given, so that the frames are the first thing to fail
    std::fs::write(d.path().join("recording.toml"), format!("{TOML}[channel]\nwidth_um = 5.0\nheight_um = 5.0\naxis_row_px = 24.0\n")).unwrap();
    let rec = Recording::open(d.path()).expect("headers are intact");
    one_line_naming(rec.load_frames(), "f_1.png");
    one_line_naming(detect_recording(&rec), "f_1.png");
}

#[test]
fn mixed_sizes_depths_or_colour_are_refused() {
    let d = tempfile::tempdir().unwrap();
    toml(d.path());
    png8(&d.path().join("f_0.png"), 0, 16, 12);
    png8(&d.path().join("f_1.png"), 0, 17, 12);
    let m = one_line_naming(Recording::open(d.path()), "f_1.png");
    assert!(m.contains("17 x 12"), "{m}");
    std::fs::remove_file(d.path().join("f_1.png")).unwrap();
    frame16(&d.path().join("f_1.png"), 0, ImageFormat::Png);
    one_line_naming(Recording::open(d.path()), "f_1.png");
    std::fs::remove_file(d.path().join("f_1.png")).unwrap();
    image::RgbImage::new(16, 12).save_with_format(d.path().join("f_1.png"), ImageFormat::Png).unwrap();
    let m = one_line_naming(Recording::open(d.path()), "f_1.png");
    assert!(m.contains("grayscale"), "{m}");
}

/// A frame's time is its place in the file-name order, so an entry named as a frame that is not
/// a readable file (a directory, a broken link) is refused naming it, not skipped (skipping it
/// shifted every later frame's time: the velocities came out 9 % high).
#[test]
fn a_frame_that_is_a_directory_or_a_broken_link_is_refused_not_skipped() {
    let d = tempfile::tempdir().unwrap();
    toml(d.path());
    for k in [0, 1, 3] {
        png8(&d.path().join(format!("f_{k}.png")), 0, 16, 12);
    }
    std::fs::create_dir(d.path().join("f_2.png")).unwrap();
    let m = one_line_naming(Recording::open(d.path()), "f_2.png");
    assert!(m.contains("directory"), "{m}");
    std::fs::remove_dir(d.path().join("f_2.png")).unwrap();
    std::os::unix::fs::symlink(d.path().join("absent.png"), d.path().join("f_2.png")).unwrap();
    one_line_naming(Recording::open(d.path()), "f_2.png");
    // a link to a frame is a frame
    std::fs::remove_file(d.path().join("f_2.png")).unwrap();
    std::os::unix::fs::symlink(d.path().join("f_1.png"), d.path().join("f_2.png")).unwrap();
    assert_eq!(Recording::open(d.path()).unwrap().frames.len(), 4);
}

#[test]
fn a_recording_without_cells_gives_a_warning_and_no_detections() {
    let d = tempfile::tempdir().unwrap();
    let mut spec = random_spec(3, 0.25, 0.01, 1.0);
    spec.cells.clear();
    spec.n_frames = 6;
    write_recording(d.path(), &spec, 3).unwrap();
    let det = detect_recording(&Recording::open(d.path()).unwrap()).unwrap();
    assert!(det.detections.is_empty(), "{:?}", det.detections.first());
    assert_eq!(det.warnings.len(), 1);
    assert!(det.warnings[0].contains("no cell"));
}

#[test]
fn walls_that_cannot_be_found_name_the_field_to_set() {
    // a flat grey recording: no walls, no axis in recording.toml
    let d = tempfile::tempdir().unwrap();
    toml(d.path());
    for i in 0..6 {
        png8(&d.path().join(format!("f_{i}.png")), 100, 32, 24);
    }
    let m = one_line_naming(detect_recording(&Recording::open(d.path()).unwrap()), "recording.toml");
    assert!(m.contains("channel.axis_row_px"), "{m}");
}

#[test]
fn a_cell_that_does_not_move_is_reported() {
    let d = tempfile::tempdir().unwrap();
    let mut spec = random_spec(8, 0.25, 0.01, 1.0);
    spec.n_frames = 8;
    spec.cells[0].velocity_mm_s = 0.0;
    write_recording(d.path(), &spec, 8).unwrap();
    let det = detect_recording(&Recording::open(d.path()).unwrap()).unwrap();
    println!("{:?}", det.warnings);
    assert!(det.warnings.iter().any(|w| w.contains("1 cell-sized stationary object")), "{:?}", det.warnings);
    // the same recording with both cells moving: no warning, cells found
    let mut spec2 = random_spec(8, 0.25, 0.01, 1.0);
    spec2.n_frames = 8;
    let d2 = tempfile::tempdir().unwrap();
    write_recording(d2.path(), &spec2, 8).unwrap();
    let det2 = detect_recording(&Recording::open(d2.path()).unwrap()).unwrap();
    assert!(det2.warnings.is_empty(), "{:?}", det2.warnings);
    assert!(!det2.detections.is_empty());
}
