//! Tests of a whole run: the CSV's header and rows, an interrupted run, a rejected scene.

use super::*;

fn short_scene(duration_s: f64) -> Scene {
    let mut s = Scene::default_scene();
    s.duration_s = duration_s;
    s.samples = (duration_s * s.rate_hz).round() as u64;
    s
}

#[test]
fn writes_the_header_and_one_row_per_sample() {
    let scene = short_scene(0.5);
    let mut buf = Vec::new();
    let stop = AtomicBool::new(false);
    let o = run(&scene, &mut buf, &RunOptions::new("mem"), &stop).unwrap();
    let text = String::from_utf8(buf).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(CSV_HEADER));
    let cols = CSV_HEADER.split(',').count();
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len() as u64, scene.samples);
    assert!(rows.iter().all(|r| r.split(',').count() == cols));
    assert_eq!(o.report.samples, 5000);
    // Every pushed level in the CSV is a detected slip start or reversal.
    let pushed = rows
        .iter()
        .filter(|r| r.split(',').nth(5) != Some("0"))
        .count();
    assert_eq!(pushed, o.report.estimator.reversals_detected);
}

#[test]
fn a_set_stop_flag_interrupts_after_flushing() {
    let scene = short_scene(1.0);
    let mut buf = Vec::new();
    let stop = AtomicBool::new(true);
    let err = run(&scene, &mut buf, &RunOptions::new("mem"), &stop).unwrap_err();
    let int = err.downcast_ref::<Interrupted>().unwrap();
    assert_eq!(int.rows, FLUSH_EVERY_ROWS);
    let text = String::from_utf8(buf).unwrap();
    assert_eq!(text.lines().count() as u64, FLUSH_EVERY_ROWS + 1);
}

#[test]
fn reversals_scenes_are_rejected_with_a_message() {
    let text =
        "duration_s = 1.0\n[structure]\nm1_kg = 29.5\nm2_kg = 1.75\nnatural_frequency_hz = 7.0\n\
                damping_ratio = 0.05\nfriction_coefficient = 0.2\n[input]\nkind = \"reversals\"\n\
                half_period_s = 0.0715\n[sampling]\nrate_hz = 1000.0\n";
    let scene = Scene::parse(text, Path::new("r.toml")).unwrap();
    let stop = AtomicBool::new(false);
    let err = run(&scene, Vec::new(), &RunOptions::new("mem"), &stop).unwrap_err();
    let msg = format!("{err:#}");
    assert!(msg.contains("r.toml") && msg.contains("reversals"), "{msg}");
}
