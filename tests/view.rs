//! The viewer: a scripted run in a virtual X display (Xvfb, on lavapipe in CI) against the
//! offscreen render of the same camera, and the present pass against its CPU mirror.

mod common;

use std::process::Command;

use lobelight::camera::View;
use lobelight::cli::compare::{Values, difference_of, read_image};
use lobelight::cpu::present::present;
use lobelight::frame::FrameConfig;
use lobelight::gpu::present::PresentPipeline;
use lobelight::gpu::scene::GpuScene;
use lobelight::gpu::tone::tone_map;
use lobelight::renderer::Renderer;
use lobelight::scene;
use lobelight::tone::ToneConfig;

/// Fails at once, naming the program and its Debian package, where `program` is not on the
/// PATH: a viewer test without it would otherwise time out waiting for a window.
fn require(program: &str, package: &str) {
    let found = std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(program).is_file()));
    assert!(
        found,
        "{program} is missing: the viewer tests need it (install the {package} package; CI does)"
    );
}

/// `xvfb-run -a` starting its search for a free display at a number of its own: two runs at
/// once from the same number can both pick it, and the second viewer then finds no X server.
fn xvfb_run() -> Command {
    require("xvfb-run", "xvfb");
    require("Xvfb", "xvfb");
    require("xauth", "xauth");
    static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let k = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let server = 100 + (std::process::id() % 100) * 20 + k;
    let mut cmd = Command::new("xvfb-run");
    cmd.args(["-n", &server.to_string()]);
    cmd
}

/// Runs the command `build` makes under a fresh `xvfb-run`, once more (up to three times in
/// all) where the program could not reach the X server it was given: `xvfb-run` starts the
/// server and the program without waiting for each other on a loaded machine, and that race,
/// not lobelight, failed one run in a few. The program says so on its stderr.
fn in_xvfb(build: impl Fn(&mut Command)) -> std::process::Output {
    in_xvfb_said(build, |run| {
        String::from_utf8_lossy(&run.stderr).into_owned()
    })
}

/// `in_xvfb`, where `said` reads what the program said (its stderr, or a log it writes).
fn in_xvfb_said(
    build: impl Fn(&mut Command),
    said: impl Fn(&std::process::Output) -> String,
) -> std::process::Output {
    let mut out = None;
    for _ in 0..3 {
        let mut cmd = xvfb_run();
        build(&mut cmd);
        let run = cmd
            .output()
            .expect("xvfb-run is missing: install the xvfb package (CI does)");
        let unreached = said(&run).contains("connection to X server");
        out = Some(run);
        if !unreached {
            break;
        }
    }
    out.expect("at least one run")
}

fn path(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("lobelight-view-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name).display().to_string()
}

const COMMON: [&str; 7] = [
    "scenes/cornell.toml",
    "--photons",
    "100000",
    "--width",
    "96",
    "--height",
    "72",
];

/// Both commands take `--spp 2` unless `extra` says otherwise: a scripted view of 3 frames
/// draws a moving frame, then two refinement frames, which hold the still image
/// `render --spp 2` writes.
fn spp(extra: &[&str]) -> &'static [&'static str] {
    if extra.contains(&"--spp") {
        &[]
    } else {
        &["--spp", "2"]
    }
}

/// `view … --frames 3 --screenshot` under `xvfb-run` with `extra` arguments: the
/// screenshot's pixels.
fn scripted_view(extra: &[&str], shot: &str) -> (Vec<[f32; 4]>, u32, u32) {
    let exe = env!("CARGO_BIN_EXE_lobelight");
    let view = in_xvfb(|c| {
        // The device's bake, as the offscreen render it is compared with.
        c.args(["-a", "-s", "-screen 0 640x480x24", exe, "view", "--gpu"])
            .args(COMMON)
            .args(extra)
            .args(spp(extra))
            .args(["--frames", "3", "--screenshot", shot]);
    });
    assert!(
        view.status.success(),
        "{}",
        String::from_utf8_lossy(&view.stderr)
    );
    let (a, w, h) = read_image(std::path::Path::new(shot)).unwrap();
    assert_eq!((w, h), (96, 72));
    (a, w, h)
}

/// `render` of the same scene and size with `extra` arguments: its pixels.
fn offscreen(extra: &[&str], out: &str) -> Vec<[f32; 4]> {
    let render = Command::new(env!("CARGO_BIN_EXE_lobelight"))
        .arg("render")
        .arg("--gpu") // the window's device, also where the CPU mirror is the faster engine
        .args(COMMON)
        .args(extra)
        .args(spp(extra))
        .args(["-o", out])
        .output()
        .unwrap();
    assert!(render.status.success());
    let (b, w, h) = read_image(std::path::Path::new(out)).unwrap();
    assert_eq!((w, h), (96, 72));
    b
}

/// Within one 8-bit step: mean relative difference under 0.5 % and every pixel within 5 %.
fn assert_one_step(a: &[[f32; 4]], b: &[[f32; 4]], w: u32, h: u32, what: &str) {
    let d = difference_of(a, b, w, h, Values::Display).unwrap();
    assert!(d.mean_relative <= 0.005, "{what}: {d:?}");
    assert!(d.within_5_percent >= 1.0, "{what}: {d:?}");
}

/// A scripted view saves what the window showed; the same scene, bake settings and size
/// rendered offscreen give the same image, for the lobes and for the reference (key R). The
/// bake and both frames are deterministic, so the tolerance is one 8-bit step.
#[test]
fn a_scripted_view_matches_the_offscreen_render() {
    for method in ["lobes", "reference"] {
        let shot = path(&format!("shot-{method}.png"));
        let (a, w, h) = scripted_view(&["--method", method], &shot);
        let b = offscreen(&["--method", method], &path("offscreen.png"));
        assert_one_step(&a, &b, w, h, method);
    }
}

/// The photon view (key M) shows the bake's photons through the tone map: the same photons
/// traced here on the device, drawn by `photon_image` and tone-mapped, give the screenshot
/// (within one 8-bit step, as above).
#[test]
fn the_photon_view_shows_the_bakes_photons() {
    let shot = path("shot-photons.png");
    let (a, w, h) = scripted_view(&["--method", "photons"], &shot);
    let device = common::device();
    let gpu = device.gpu().unwrap();
    let mut scene = scene::load(std::path::Path::new(COMMON[0])).unwrap();
    scene.bake.photons = 100_000;
    let view = View::new(&scene.camera, w, h);
    let renderer = Renderer::new(std::sync::Arc::new(scene), &device).unwrap();
    let seen = renderer
        .photon_view(&view, &FrameConfig::default(), &mut |_, _| {})
        .unwrap();
    let hdr = gpu.storage("photon view", &seen.hdr).unwrap();
    let mut encoder = gpu.encoder("photon view tone map");
    let toned = tone_map(gpu, &mut encoder, &hdr, w * h, &ToneConfig::default()).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let rgba: Vec<u32> = gpu.read(&toned.rgba, (w * h) as usize).unwrap();
    // What the PNG holds: the bytes over 255.
    let b: Vec<[f32; 4]> = rgba
        .iter()
        .map(|p| std::array::from_fn(|c| ((p >> (8 * c)) & 0xff) as f32 / 255.0))
        .collect();
    assert_one_step(&a, &b, w, h, "photon view");
}

/// On a GL-only machine the viewer runs on GL: its scripted view matches the Vulkan
/// offscreen render (the GL fallback traces the same photons; tests/cli.rs) within the
/// tolerance above, but for one pixel in a thousand. Both draw moving frames (`--spp 0`): a
/// per-pixel shadow ray that grazes a disk's rim can go either way between two drivers' float
/// paths and move a pixel by a sixteenth of its direct light, where the direct bake's rays
/// are blended away. And a pixel on a block's edge shows the one surface whose splat is
/// nearest (the front target, `same_surface`), as a ray tracer's pixel does: where the nearest
/// splats of the two faces lie within the drivers' rounding of each other, the two drivers
/// may pick different faces (4 pixels of 6,912 here).
#[test]
fn the_viewer_runs_on_gl() {
    let moving = ["--spp", "0"];
    let (a, w, h) = scripted_view(
        &["--backend", "gl", moving[0], moving[1]],
        &path("shot-gl.png"),
    );
    let b = offscreen(
        &["--backend", "vulkan", moving[0], moving[1]],
        &path("offscreen-vk.png"),
    );
    let d = difference_of(&a, &b, w, h, Values::Display).unwrap();
    assert!(d.mean_relative <= 0.005, "GL window against Vulkan: {d:?}");
    assert!(
        d.within_5_percent >= 0.999,
        "GL window against Vulkan: {d:?}"
    );
}

/// `bench frame --window` adds the window's figures (swap chain included) under `window`,
/// and every size has the present pass's time.
#[test]
fn bench_frame_window_reports_the_window() {
    let exe = env!("CARGO_BIN_EXE_lobelight");
    let out = in_xvfb(|c| {
        c.args(["-a", "-s", "-screen 0 1600x900x24", exe, "bench", "frame"])
            .args([
                "scenes/cornell.toml",
                "--photons",
                "20000",
                "--area-samples",
                "1",
                "--orbit",
                "0",
            ])
            .args(["--window", "--json"]);
    });
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let sizes = r["sizes"].as_array().unwrap();
    assert!(
        sizes
            .iter()
            .any(|s| s["width"] == 1280 && s["height"] == 720)
    );
    assert!(
        sizes
            .iter()
            .all(|s| s["present_ms"].as_f64().unwrap() > 0.0)
    );
    let w = &r["window"];
    assert_eq!(
        (w["width"].as_u64(), w["height"].as_u64()),
        (Some(1280), Some(720))
    );
    assert!(w["frame_ms"].as_f64().unwrap() > 0.0, "{w}");
    assert!(w["frames"].as_u64().unwrap() >= 10, "{w}");
}

/// `bench frame --window --target-ms` turns the camera in the window every frame; with a
/// target no frame meets, the viewer steps its moving frames down to the smallest internal
/// size, one step every two frames after the first (the first frame at a size makes its
/// targets and moves nothing), and the checked frames, upsampled, are measured against their still images.
#[test]
fn the_window_orbit_steps_down_to_its_target() {
    let exe = env!("CARGO_BIN_EXE_lobelight");
    let out = in_xvfb(|c| {
        c.args(["-a", "-s", "-screen 0 1600x900x24", exe, "bench", "frame"])
            .args(["scenes/cornell.toml", "--photons", "20000"])
            .args(["--area-samples", "1", "--orbit", "0"])
            .args(["--window", "--target-ms", "1", "--json"]);
    });
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let w = &r["window_orbit"];
    assert_eq!(w["frames"].as_u64(), Some(30), "{w}");
    let widths: Vec<u64> = w["drawn"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d[0].as_u64().unwrap())
        .collect();
    // The window's size once, then each smaller size twice, down to an eighth of the width.
    let expected: Vec<u64> = std::iter::once(1280)
        .chain([905, 640, 453, 320, 227].iter().flat_map(|&x| [x, x]))
        .chain(std::iter::repeat(160))
        .take(30)
        .collect();
    assert_eq!(widths, expected, "{w}");
    // Then at that size the merged disks widen by √2 a step, twice each, to four times the
    // scene's level of detail.
    let lods: Vec<f64> = w["lod"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_f64().unwrap())
        .collect();
    let base = lods[0];
    let expected: Vec<f64> = std::iter::repeat_n(1.0, 13)
        .chain([1.414, 2.0, 2.828].iter().flat_map(|&x| [x, x]))
        .chain(std::iter::repeat(4.0))
        .take(30)
        .collect();
    assert!(base > 0.0, "{w}");
    assert!(
        lods.iter()
            .zip(&expected)
            .all(|(l, e)| (l / base - e).abs() < 1e-3),
        "{w}"
    );
    let rel_mse = w["rel_mse"].as_array().unwrap();
    assert_eq!(rel_mse.len(), 3, "{w}");
    // A 160-pixel-wide frame upsampled eightfold is far from its still image, but not black.
    assert!(
        rel_mse
            .iter()
            .all(|e| e.as_f64().is_some_and(|e| e > 0.0 && e < 1.0)),
        "{w}"
    );
}

/// The present pass drawn into an offscreen texture of a plain and of an sRGB format, read
/// back, against the mirror: within one 8-bit step, for an image of the target's size (each
/// pixel its own) and for a smaller one upsampled (a moving frame at a lower internal
/// resolution).
#[test]
fn the_present_pass_matches_its_mirror() {
    let gpu = common::gpu();
    let target = (64u32, 48u32);
    for image in [target, (27, 19)] {
        let rgba: Vec<u32> = (0..image.0 * image.1)
            .map(|i| (i * 2654435761) | 0xff00_0000)
            .collect();
        for format in [
            wgpu::TextureFormat::Rgba8Unorm,
            wgpu::TextureFormat::Rgba8UnormSrgb,
        ] {
            let got = present_on_device(&gpu, format, &rgba, image, target);
            let pipeline = PresentPipeline::new(&gpu, format).unwrap();
            let want = present(&pipeline.params(image, target), &rgba);
            for (i, (g, m)) in got.iter().zip(&want).enumerate() {
                for (c, &value) in m[..3].iter().enumerate() {
                    // What the texture stores: the mirror's value, sRGB-encoded for an sRGB
                    // format.
                    let v = if format.is_srgb() {
                        lobelight::shared::tone::srgb_byte(value) as i32
                    } else {
                        (value * 255.0).round() as i32
                    };
                    let stored = ((g >> (8 * c)) & 0xff) as i32;
                    assert!(
                        (stored - v).abs() <= 1,
                        "{image:?} {format:?} pixel {i} channel {c}: {stored} vs {v}"
                    );
                }
            }
            if image == target && !format.is_srgb() {
                // Each pixel its own: the bytes come back as they went in.
                let same = got.iter().zip(&rgba).all(|(g, p)| g == p);
                assert!(
                    same,
                    "the present pass changed an image of the target's size"
                );
            }
        }
    }
}

/// `rgba` (`image` pixels) drawn by the present pass onto a texture of `format` and `target`
/// pixels, read back.
fn present_on_device(
    gpu: &lobelight::gpu::Gpu,
    format: wgpu::TextureFormat,
    rgba: &[u32],
    image: (u32, u32),
    (w, h): (u32, u32),
) -> Vec<u32> {
    let buffer = gpu.storage("image", rgba).unwrap();
    let pipeline = PresentPipeline::new(gpu, format).unwrap();
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("present target"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let out = gpu.storage_zeroed("read back", (w * h * 4) as u64).unwrap();
    let mut encoder = gpu.encoder("present test");
    let view = texture.create_view(&Default::default());
    pipeline.record(gpu, &mut encoder, &view, &buffer, image, (w, h));
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &out,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 4),
                rows_per_image: Some(h),
            },
        },
        texture.size(),
    );
    gpu.submit_and_wait(encoder).unwrap();
    gpu.read(&out, (w * h) as usize).unwrap()
}

/// With `--cache` the first run bakes and saves; the second loads the lobes at start (no bake)
/// and shows the same image.
#[test]
fn the_viewer_starts_from_the_bake_cache() {
    let exe = env!("CARGO_BIN_EXE_lobelight");
    let cache = path("view.cache");
    std::fs::remove_file(&cache).ok();
    let run = |shot: &str| {
        let out = in_xvfb(|c| {
            c.args([
                "-a",
                "-s",
                "-screen 0 640x480x24",
                exe,
                "view",
                "scenes/cornell.toml",
            ])
            .args(["--photons", "50000", "--width", "64", "--height", "48"])
            .args(["--frames", "1", "--screenshot", shot, "--cache", &cache]);
        });
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{stderr}");
        stderr
    };
    let (first, second) = (path("first.png"), path("second.png"));
    run(&first);
    assert!(std::path::Path::new(&cache).exists());
    let log = run(&second);
    assert!(log.contains("bake 0.0 s"), "{log}");
    let (a, w, h) = read_image(std::path::Path::new(&first)).unwrap();
    let (b, _, _) = read_image(std::path::Path::new(&second)).unwrap();
    let d = difference_of(&a, &b, w, h, Values::Display).unwrap();
    assert_eq!(d.max_relative, 0.0, "{d:?}");
}

/// The viewer's background bake of a moved light: a preview pass (an eighth of the photons,
/// fewer EM iterations), then the full pass, whose lobes are the very ones `bake` gives for
/// the moved scene (the bake is deterministic). A newer bake makes an older one stop before
/// its next pass.
#[test]
fn a_moved_light_bakes_a_preview_then_in_full() {
    use std::sync::Arc;
    use std::sync::atomic::AtomicU64;

    use lobelight::bake::{BakeDevice, Progress, bake};
    use lobelight::cli::view::{move_first_light, passes};
    use lobelight::renderer::{BakeEngine, BakeResult, Baking, Engine, Renderer};

    let gpu = Arc::new(common::gpu());
    let mut scene = scene::load(std::path::Path::new(COMMON[0])).unwrap();
    scene.bake.photons = 200_000;
    let moved = Arc::new(move_first_light(&scene, 1.0, 0.0).unwrap());
    assert_ne!(moved.lights[0].position, scene.lights[0].position);
    let on_gpu = Arc::new(GpuScene::upload(&gpu, &moved).unwrap());
    let renderer = Renderer::new(moved.clone(), &Engine::Device(gpu.clone())).unwrap();
    let generation = Arc::new(AtomicU64::new(0));
    let wait = |baking: &mut Baking| -> Vec<BakeResult> {
        let mut got = Vec::new();
        let start = std::time::Instant::now();
        while got.last().is_none_or(|r: &BakeResult| r.preview) {
            match baking.poll() {
                Ok(Some(r)) => got.push(r),
                Ok(None) => std::thread::sleep(std::time::Duration::from_millis(10)),
                Err(_) => break, // the bake stopped
            }
            assert!(start.elapsed().as_secs() < 600, "the bake never finished");
        }
        got
    };
    let plan = passes(&moved.bake, true);
    assert_eq!(plan.len(), 2);
    assert_eq!(plan[0].photons, 25_000);
    assert!(plan[0].iterations < plan[1].iterations);
    // An older bake, then a newer one at once: the older stops after its first pass at most.
    let spawn = |plan| {
        let engine = BakeEngine::Device;
        (renderer.spawn_bake(&engine, &moved, (plan, None), &generation)).unwrap()
    };
    let mut older = spawn(plan.clone());
    let mut newer = spawn(plan);
    let results = wait(&mut newer);
    assert_eq!(results.len(), 2);
    assert!(results[0].preview && !results[1].preview);
    assert_eq!(results[0].emitted, 25_000);
    assert_eq!(results[1].emitted, 200_000);
    let stale = wait(&mut older);
    assert!(stale.iter().all(|r| r.preview), "a stopped bake finished");
    let quiet = Progress::new(false);
    let direct = bake(&moved, BakeDevice::Gpu(&gpu, &on_gpu), &quiet).unwrap();
    let full = &results[1].lobes;
    assert_eq!(full.light, direct.lobes.light);
    assert_eq!(full.lobes, direct.lobes.lobes);
}

/// The keys, pressed for real (xdotool under Xvfb): R shows the reference, M the photon view,
/// P saves each, the right arrow moves the light and bakes a preview then in full, Esc quits.
/// Each step waits for the window's title to say it happened (no fixed sleeps).
#[test]
fn the_keys_switch_views_move_the_light_and_quit() {
    require("xdotool", "xdotool");
    let exe = env!("CARGO_BIN_EXE_lobelight");
    let dir = std::path::PathBuf::from(path("keys"));
    std::fs::create_dir_all(&dir).unwrap();
    let script = format!(
        r#"
set -e
"{exe}" view "{scene}" --photons 300000 --width 160 --height 120 > "{log}" 2>&1 &
viewer=$!
title() {{ xdotool getwindowname "$win" 2>/dev/null || true; }}
until_title() {{
  for i in $(seq 1 1200); do
    case "$(title)" in *"$1"*) return 0 ;; esac
    sleep 0.1
  done
  echo "timed out waiting for: $1 (title: $(title))" >&2; kill $viewer; exit 1
}}
# Press a key until the title shows what it does: under load an X event can be lost, and a
# key that toggles must not be pressed twice, so each press gets 10 s to show.
press() {{
  for k in $(seq 1 12); do
    xdotool windowfocus --sync "$win"
    xdotool key "$1"
    for i in $(seq 1 100); do
      case "$(title)" in *"$2"*) return 0 ;; esac
      sleep 0.1
    done
  done
  echo "timed out waiting for: $2 after key $1 (title: $(title))" >&2; kill $viewer; exit 1
}}
for i in $(seq 1 600); do
  win=$(xdotool search --name lobelight 2>/dev/null | head -1) && [ -n "$win" ] && break
  kill -0 $viewer 2>/dev/null || {{ echo "the viewer exited before its window showed" >&2; exit 1; }}
  sleep 0.1
done
until_title "global illumination"
press r "Reference"
xdotool key p
press m "Photons"
xdotool key p
press m "Lobes"
press Right "baking"
until_title "global illumination"
xdotool key Escape
wait $viewer
"#,
        log = dir.join("log.txt").display(),
        scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell.toml"),
    );
    // The viewer writes its own log, where it says it could not reach the X server.
    let read_log = || std::fs::read_to_string(dir.join("log.txt")).unwrap_or_default();
    let out = in_xvfb_said(
        |c| {
            c.args(["-a", "-s", "-screen 0 640x480x24", "bash", "-c", &script])
                // Screenshots (P) land in the working directory.
                .current_dir(&dir);
        },
        |_| read_log(),
    );
    let log = read_log();
    assert!(
        out.status.success(),
        "{}\n{log}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(log.contains("preview bake: 37500 photons"), "{log}");
    assert_eq!(log.matches("bake: 300000 photons").count(), 2, "{log}");
    assert_eq!(log.matches("wrote ").count(), 2, "{log}");
    for shot in ["lobelight-1.png", "lobelight-2.png"] {
        let (pixels, w, h) = read_image(&dir.join(shot)).unwrap();
        assert_eq!((w, h), (160, 120));
        assert!(pixels.iter().any(|p| p[0] > 0.0), "{shot} is black");
    }
}
