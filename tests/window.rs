//! The `window` example in a real window: run under Xvfb for five frames, its screenshot (the
//! presented surface texture, copied before present) must match the same frame rendered
//! offscreen on an application-owned device.

#[path = "../examples/window.rs"]
#[allow(dead_code)]
mod window;

mod common;

use std::process::Command;

#[test]
fn window_screenshot_matches_the_offscreen_frame() {
    let frames = 5;
    let shot = std::env::temp_dir().join(format!("fieldkit_window_{}.png", std::process::id()));
    let output = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(common::example_binary("window"))
        .args(["--frames", &frames.to_string(), "--screenshot"])
        .arg(&shot)
        .output()
        .unwrap_or_else(|e| {
            panic!("this test runs the window example under Xvfb: apt-get install -y xvfb ({e})")
        });
    let log = String::from_utf8_lossy(&output.stderr);
    eprintln!("{log}");
    assert!(output.status.success(), "the window example failed: {log}");
    let got = image::open(&shot).expect("the screenshot").to_rgba8();
    std::fs::remove_file(&shot).ok();
    assert_eq!(got.dimensions(), (window::SIZE[0], window::SIZE[1]));

    let (device, queue) = {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY),
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let adapter = pollster::block_on(instance.request_adapter(&Default::default()))
            .unwrap_or_else(|e| {
                panic!(
                    "this test needs a GPU adapter (apt-get install -y mesa-vulkan-drivers): {e}"
                )
            });
        pollster::block_on(adapter.request_device(&Default::default())).expect("a device")
    };
    let want = window::render_offscreen(
        &device,
        &queue,
        wgpu::TextureFormat::Rgba8Unorm,
        window::frame_time(frames - 1),
    )
    .expect("the offscreen frame");

    // Same adapter, same frame: the presented image holds what the passes wrote. Set on
    // llvmpipe (the swapchain is B8G8R8A8_UNORM there, swizzled back to RGBA): mean 0 and no
    // pixel off. The tolerance allows another GPU's presentation path a rounding step in a
    // few pixels; a missing metaball surface or floor moves thousands of pixels by far more.
    let mut worst = 0u8;
    let mut off = 0usize;
    let mut sum = 0u64;
    for (g, w) in got.as_raw().chunks(4).zip(want.chunks(4)) {
        let d = (0..3).map(|c| g[c].abs_diff(w[c])).max().unwrap_or(0);
        worst = worst.max(d);
        sum += d as u64;
        if d > 2 {
            off += 1;
        }
    }
    let pixels = want.len() / 4;
    let mean = sum as f64 / pixels as f64;
    eprintln!(
        "screenshot against offscreen: mean {mean:.4}, worst {worst}, {off} pixels off by more than 2"
    );
    assert!(mean <= 0.05, "mean difference {mean}");
    assert!(
        off <= pixels / 1000,
        "{off} of {pixels} pixels differ by more than 2 levels"
    );

    // The frame is not trivially equal: the floor and the surface are both in it.
    let distinct: std::collections::HashSet<&[u8]> = want.chunks(4).collect();
    assert!(distinct.len() > 100, "{} distinct colours", distinct.len());
}
