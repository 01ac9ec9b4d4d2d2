//! The `lobelight` binary: `info` on the shipped scenes, its JSON keys (a contract), the GL
//! fallback, and one-line errors with a non-zero exit.

mod common;

use std::process::{Command, Output};

fn lobelight(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lobelight"));
    cmd.args(args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("run lobelight")
}

fn json(args: &[&str]) -> serde_json::Value {
    let out = lobelight(args, &[]);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON object")
}

#[test]
fn info_json_has_the_documented_keys() {
    let v = json(&["info", "scenes/cornell.toml", "--json"]);
    for key in [
        "scene",
        "adapter",
        "backend",
        "splats",
        "lights",
        "materials",
        "glossy",
        "bounds",
        "grid",
        "memory_bytes",
    ] {
        assert!(v.get(key).is_some(), "missing key {key}: {v}");
    }
    assert_eq!(v["lights"], 1);
    assert_eq!(v["glossy"], true);
    assert!(v["splats"].as_u64().unwrap() > 30_000);
    let grid = &v["grid"];
    assert!(grid["entries"].as_u64().unwrap() >= v["splats"].as_u64().unwrap());
    assert!(grid["occupied_cells"].as_u64().unwrap() > 0);
    assert_ne!(v["backend"], "cpu");
}

#[test]
fn gpu_and_cpu_info_agree() {
    let gpu = json(&["info", "scenes/cornell_spheres.toml", "--json"]);
    let cpu = json(&["info", "scenes/cornell_spheres.toml", "--json", "--cpu"]);
    assert_eq!(cpu["backend"], "cpu");
    for key in ["entries", "occupied_cells", "max_cell_len", "dims"] {
        assert_eq!(gpu["grid"][key], cpu["grid"][key], "{key}");
    }
}

#[test]
fn gl_backend_builds_the_same_grid() {
    // The fallback for machines with Mesa's OpenGL but no Vulkan driver.
    let gl = json(&["info", "scenes/diffuse.toml", "--json", "--backend", "gl"]);
    assert_eq!(gl["backend"], "gl");
    let cpu = json(&["info", "scenes/diffuse.toml", "--json", "--cpu"]);
    assert_eq!(gl["grid"]["entries"], cpu["grid"]["entries"]);
}

#[test]
fn no_vulkan_driver_says_how_to_install_one() {
    let out = lobelight(
        &["info", "scenes/diffuse.toml", "--backend", "vulkan"],
        &[
            ("VK_ICD_FILENAMES", "/nonexistent.json"),
            ("VK_DRIVER_FILES", "/nonexistent.json"),
        ],
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no GPU adapter") && err.contains("mesa-vulkan-drivers"),
        "{err}"
    );
}

#[test]
fn errors_are_one_line_with_non_zero_exit() {
    let out = lobelight(&["info", "scenes/does_not_exist.toml"], &[]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("lobelight:"))
        .collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].contains("scenes/does_not_exist.toml"), "{err}");
}

/// Where a command writes is checked before its work (the scene is not even loaded): an image
/// in a folder that does not exist, an image path that names a folder, a cache in a missing
/// folder, a viewer's screenshot likewise. Each is one line naming the path.
#[test]
fn outputs_are_checked_before_the_work() {
    let dir = std::env::temp_dir().join("lobelight-outputs");
    std::fs::create_dir_all(&dir).unwrap();
    let folder = dir.display().to_string();
    let missing = dir.join("missing/out.png").display().to_string();
    let cache = dir.join("missing/bake.cache").display().to_string();
    // A scene that does not exist: were the scene read first, its error would come instead.
    let cases: [(&[&str], &str); 4] = [
        (
            &["render", "scenes/nope.toml", "-o", &missing],
            "does not exist; create it first",
        ),
        (
            &["render", "scenes/nope.toml", "-o", &folder],
            "names a folder",
        ),
        (
            &[
                "render",
                "scenes/nope.toml",
                "-o",
                "x.png",
                "--cache",
                &cache,
            ],
            "does not exist; create it first",
        ),
        (
            &[
                "view",
                "scenes/nope.toml",
                "--frames",
                "1",
                "--screenshot",
                &missing,
            ],
            "does not exist; create it first",
        ),
    ];
    for (args, says) in cases {
        let out = lobelight(args, &[]);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(
            !err.contains("nope.toml"),
            "{args:?}: the scene was read first: {err}"
        );
    }
    assert!(
        !std::path::Path::new("x.png").exists(),
        "the probe left its file"
    );
}

/// `bench frame`: its keys, timed with the passes apart (the temporal pass too) and with the
/// level of detail that moving frames draw with by default (whose merge tree must be built for
/// those frames too), and a two-frame orbit.
#[test]
fn bench_frame_json_has_the_documented_keys() {
    let v = json(&[
        "bench",
        "frame",
        "scenes/cornell.toml",
        "--photons",
        "20000",
        "--taa",
        "--orbit",
        "2",
        "--json",
    ]);
    for key in [
        "adapter",
        "backend",
        "direct",
        "splatter",
        "lod",
        "glossy_rays",
        "frame_ms",
        "sizes",
        "refinement",
        "orbit",
    ] {
        assert!(v.get(key).is_some(), "missing key {key}: {v}");
    }
    assert_eq!(v["lod"], 1.5);
    assert_eq!(v["glossy_rays"], 4);
    for size in v["sizes"].as_array().unwrap() {
        assert_eq!(
            size["passes_ms"].as_array().map(Vec::len),
            Some(3),
            "{size}"
        );
        assert!(size["frame_ms"].as_f64().unwrap() > 0.0, "{size}");
        assert!(size["temporal_ms"].as_f64().unwrap() > 0.0, "{size}");
    }
    assert!(
        v["refinement"]["moving_rel_mse"].as_f64().unwrap() > 0.0,
        "{v}"
    );
    // The orbit: both frames against their still images, with the temporal pass and alone;
    // the first frame has no history, so both are the same image there.
    let orbit = &v["orbit"];
    assert_eq!(orbit["frames"], 2, "{orbit}");
    let (with, alone) = (&orbit["rel_mse"], &orbit["rel_mse_alone"]);
    assert_eq!(with.as_array().map(Vec::len), Some(2), "{orbit}");
    assert_eq!(with[0], alone[0], "{orbit}");
    assert!(orbit["median_rel_mse"].as_f64().unwrap() > 0.0, "{orbit}");
}

#[test]
fn bench_em_json_has_the_documented_keys() {
    let args = [
        "bench",
        "em",
        "scenes/cornell.toml",
        "--photons",
        "20000",
        "--iterations",
        "3",
        // The thesis's family and five lobes, which these pruning figures were measured with:
        // with the default vMF (its priors) and eight lobes, three iterations leave the fixed
        // fit short of converged, and the pruned one may fit closer.
        "--family",
        "ward",
        "--lobes",
        "5",
        "--json",
    ];
    let gpu = json(&args);
    for key in [
        "fits_per_s",
        "em_ms",
        "binning_ms",
        "photons_ms",
        "splats_fitted",
        "mean_photons",
        "nll",
        "family",
        "lobes",
        "iterations",
        "search_radius",
        "stats",
        "skipping",
        "pruning",
    ] {
        assert!(gpu.get(key).is_some(), "missing key {key}: {gpu}");
    }
    // Pruning (the default) keeps fewer lobes than a fixed count of five on every fitted
    // splat, each fitting its photons less closely but within the penalty.
    let p = &gpu["pruning"];
    assert_eq!(p["prune"], true);
    let (kept, fixed) = (
        p["lobes"].as_u64().unwrap(),
        p["fixed_lobes"].as_u64().unwrap(),
    );
    assert!(
        0 < kept && kept < fixed,
        "{kept} lobes pruned, {fixed} fixed"
    );
    assert!(
        p["nll"].as_f64().unwrap() >= p["fixed_nll"].as_f64().unwrap() - 1e-3,
        "{p}"
    );
    assert!(p["fixed_em_ms"].as_f64().unwrap() > 0.0);
    // The render's fit skips the diffuse splats: fewer fitted, and only their lobes kept.
    let k = &gpu["skipping"];
    assert!(k["splats_fitted"].as_u64().unwrap() < gpu["splats_fitted"].as_u64().unwrap());
    assert!(k["em_ms"].as_f64().unwrap() > 0.0);
    let (kept, all) = (
        k["lobe_bytes"].as_u64().unwrap(),
        k["lobe_bytes_fit_all"].as_u64().unwrap(),
    );
    assert!(0 < kept && kept < all, "{kept} of {all} lobe bytes");
    assert_eq!(gpu["family"], "ward", "the default family");
    assert_eq!(gpu["iterations"], 3);
    assert!(gpu["fits_per_s"].as_f64().unwrap() > 0.0);
    assert!(gpu["splats_fitted"].as_u64().unwrap() > 1000);
    let mut cpu_args = args.to_vec();
    cpu_args.push("--cpu");
    let cpu = json(&cpu_args);
    assert_eq!(cpu["backend"], "cpu");
    // Different photons (the traces differ by rare rounding) and a different workgroup size:
    // the fit errors agree closely, not bit for bit.
    let (g, c) = (gpu["nll"].as_f64().unwrap(), cpu["nll"].as_f64().unwrap());
    assert!((g - c).abs() <= 0.01 * c.abs(), "nll: GPU {g}, CPU {c}");
}

#[test]
fn bench_photons_json_has_the_documented_keys() {
    let args = [
        "bench",
        "photons",
        "scenes/cornell.toml",
        "--photons",
        "20000",
        "--json",
    ];
    let gpu = json(&args);
    for key in [
        "photons_per_s",
        "emitted",
        "stored",
        "stored_ratio",
        "photons_per_splat",
        "search_radius",
        "stats",
        "stages",
    ] {
        assert!(gpu.get(key).is_some(), "missing key {key}: {gpu}");
    }
    for key in ["grid_ms", "trace_ms", "download_ms"] {
        assert!(
            gpu["stages"][key].as_f64().is_some(),
            "missing stages.{key}: {gpu}"
        );
    }
    assert_eq!(gpu["emitted"], 20000);
    assert!(gpu["photons_per_s"].as_f64().unwrap() > 0.0);
    let mut cpu_args = args.to_vec();
    cpu_args.push("--cpu");
    let cpu = json(&cpu_args);
    assert_eq!(cpu["backend"], "cpu");
    // Same random numbers, same paths: the counts agree up to rare rounding-sized differences.
    let (g, c) = (
        gpu["stored"].as_f64().unwrap(),
        cpu["stored"].as_f64().unwrap(),
    );
    assert!((g - c).abs() <= 1e-3 * c, "stored: GPU {g}, CPU {c}");
}

#[test]
fn gl_backend_traces_the_same_photons() {
    let args = [
        "bench",
        "photons",
        "scenes/diffuse.toml",
        "--photons",
        "20000",
        "--json",
    ];
    let mut gl_args = args.to_vec();
    gl_args.extend(["--backend", "gl"]);
    let gl = json(&gl_args);
    assert_eq!(gl["backend"], "gl");
    let mut cpu_args = args.to_vec();
    cpu_args.push("--cpu");
    let cpu = json(&cpu_args);
    let (g, c) = (
        gl["stored"].as_f64().unwrap(),
        cpu["stored"].as_f64().unwrap(),
    );
    assert!((g - c).abs() <= 1e-3 * c, "stored: GL {g}, CPU {c}");
}

#[test]
fn render_photons_writes_a_png() {
    let dir = std::env::temp_dir().join(format!("lobelight-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("photons.png");
    let v = json(&[
        "render",
        "scenes/cornell.toml",
        "--method",
        "photons",
        "--photons",
        "20000",
        "--width",
        "64",
        "--height",
        "48",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(v["stages"]["photons"]["ran"], true);
    assert_eq!(v["stages"]["photons"]["emitted"], 20000);
    assert_eq!(v["stages"]["em"]["ran"], false);
    assert!(v["stages"]["em"]["skipped_reason"].is_string());
    let img = image::open(&out).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (64, 48));
    let lit = img.pixels().filter(|p| p.0.iter().any(|&c| c > 0)).count();
    assert!(lit > 64 * 48 / 4, "only {lit} pixels show photons");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn impossible_photon_counts_are_clear_errors() {
    for n in ["0", "5000000000"] {
        let out = lobelight(
            &[
                "bench",
                "photons",
                "scenes/cornell.toml",
                "--photons",
                n,
                "--cpu",
            ],
            &[],
        );
        assert_eq!(out.status.code(), Some(1));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("photons must be within 1..="), "{err}");
    }
}

/// `render` (method lobes): PNG and EXR, the stage keys, a cache that a new view reuses and
/// a bake change invalidates, and `compare` on the two EXRs.
#[test]
fn render_lobes_png_exr_and_cache() {
    let dir = std::env::temp_dir().join(format!("lobelight-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let render = |out: &str, extra: &[&str]| {
        let mut args = vec![
            "render",
            "scenes/cornell.toml",
            "--photons",
            "30000",
            "--width",
            "64",
            "--height",
            "48",
            "-o",
            out,
            "--json",
        ];
        args.extend_from_slice(extra);
        // The device, also where it is a software rasterizer: the test compares it with the
        // CPU mirror.
        if !extra.contains(&"--cpu") {
            args.push("--gpu");
        }
        json(&args)
    };
    let cache = path("bake.cache");
    let png = path("a.png");
    let v = render(&png, &["--cache", &cache]);
    assert_eq!(v["method"], "lobes");
    assert_eq!(v["cache_hit"], false);
    for stage in ["grid", "photons", "binning", "em", "shade", "tonemap"] {
        assert_eq!(v["stages"][stage]["ran"], true, "{stage}");
    }
    let em = &v["stages"]["em"];
    assert!(em["splats_fitted"].as_u64().unwrap() > 0);
    let kept = em["lobes_kept"].as_u64().unwrap();
    assert!(
        0 < kept && kept < em["lobes_fitted"].as_u64().unwrap(),
        "{em}"
    );
    assert!(v["log_average"].as_f64().unwrap() > 0.0);
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (64, 48));
    // The same bake from the cache, linear HDR out; then with the CPU mirror.
    let exr = path("a.exr");
    let v = render(&exr, &["--cache", &cache]);
    assert_eq!(v["cache_hit"], true);
    assert_eq!(v["stages"]["em"]["ran"], false);
    assert_eq!(v["stages"]["tonemap"]["ran"], false);
    let cpu_exr = path("cpu.exr");
    let v = render(&cpu_exr, &["--cache", &cache, "--cpu"]);
    assert_eq!(v["cache_hit"], true);
    let d = json(&["compare", &exr, &cpu_exr, "--json"]);
    assert!(d["mean_relative"].as_f64().unwrap() <= 0.01, "{d}");
    assert!(d["within_5_percent"].as_f64().unwrap() >= 0.99, "{d}");
    // The standard metrics agree: GPU and CPU mirror differ by rounding.
    assert!(d["rel_mse"].as_f64().unwrap() <= 1e-3, "{d}");
    assert!(d["smape"].as_f64().unwrap() <= 0.01, "{d}");
    assert!(d["psnr"].as_f64().unwrap() >= 40.0, "{d}");
    assert!(d["flip"].as_f64().unwrap() <= 0.01, "{d}");
    // A bake setting changed: the cache is stale and the bake runs again.
    let v = render(&png, &["--cache", &cache, "--iterations", "3"]);
    assert_eq!(v["cache_hit"], false);
    assert_eq!(v["stages"]["em"]["ran"], true);
    // A fixed lobe count is a bake setting too: five lobes on every fitted splat that has
    // photons, none pruned.
    let v = render(&png, &["--cache", &cache, "--fixed-lobes"]);
    assert_eq!(v["cache_hit"], false);
    let em = &v["stages"]["em"];
    assert!(em["lobes_kept"].as_u64().unwrap() > kept, "{em}");
    assert!(em["lobes_kept"].as_u64().unwrap() <= em["lobes_fitted"].as_u64().unwrap());
    // Unknown extensions are refused before any work.
    let out = lobelight(
        &["render", "scenes/cornell.toml", "-o", &path("a.jpg")],
        &[],
    );
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains(".png"));
    std::fs::remove_dir_all(&dir).ok();
}

/// A reader that goes away (`lobelight … | head -1`) ends the output, not the process with a
/// panic.
#[test]
fn a_closed_stdout_is_not_a_panic() {
    let dir = std::env::temp_dir().join(format!("lobelight-pipe-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("a.png");
    image::RgbImage::from_pixel(16, 16, image::Rgb([90, 120, 200]))
        .save(&png)
        .unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_lobelight"))
        .args([
            "compare",
            png.to_str().unwrap(),
            png.to_str().unwrap(),
            "--json",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `bench rebake`: a preview with an eighth of the photons and fewer EM iterations, then the
/// full re-bake, over light moves; the preview's frame differs from the full one, but not
/// wildly (relMSE under 0.5 on the Cornell box at 25 k photons).
#[test]
fn bench_rebake_json_has_the_documented_keys() {
    let r = json(&[
        "bench",
        "rebake",
        "scenes/cornell.toml",
        "--photons",
        "200000",
        "--json",
    ]);
    for key in [
        "rebake_ms",
        "preview_ms",
        "bake_ms",
        "grid_ms",
        "photons_per_s",
        "preview_rel_mse",
        "preview_photons",
        "preview_iterations",
        "moves",
    ] {
        assert!(r.get(key).is_some(), "missing key {key}: {r}");
    }
    assert_eq!(r["photons"], 200_000);
    assert_eq!(r["preview_photons"], 25_000);
    let e = r["preview_rel_mse"].as_f64().unwrap();
    assert!(e > 0.0 && e < 0.5, "preview relMSE {e}");
    // Too few photons for a preview is a clear error.
    let out = lobelight(
        &[
            "bench",
            "rebake",
            "scenes/cornell.toml",
            "--photons",
            "1000",
        ],
        &[],
    );
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("preview"));
}

/// An image larger than the device can bind is refused at once, before the bake, with what
/// the device holds.
#[test]
fn an_image_beyond_the_device_is_refused_before_baking() {
    let out = lobelight(
        &[
            "render",
            "scenes/cornell.toml",
            "--gpu",
            "--width",
            "16384",
            "--height",
            "16384",
            "-o",
            "/tmp/lobelight-too-big.png",
        ],
        &[],
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("largest storage binding"), "{err}");
    assert!(!err.contains("photons"), "it baked first: {err}");
}

/// A cache file whose lobe offsets point past its lobes is refused as not a cache, not read.
#[test]
fn a_corrupt_cache_is_a_clear_error() {
    let dir = std::env::temp_dir().join(format!("lobelight-cache-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cache = dir.join("c.cache").display().to_string();
    let png = dir.join("c.png").display().to_string();
    let args = [
        "render",
        "scenes/cornell.toml",
        "--photons",
        "20000",
        "--width",
        "32",
        "--height",
        "32",
        "--cache",
        &cache,
        "-o",
        &png,
    ];
    assert!(lobelight(&args, &[]).status.success());
    let mut bytes = std::fs::read(&cache).unwrap();
    // The last splat's `first_lobe` (the last 4 bytes) far past the stored lobes.
    let at = bytes.len() - 4;
    bytes[at..].copy_from_slice(&u32::MAX.to_le_bytes());
    std::fs::write(&cache, &bytes).unwrap();
    let out = lobelight(&args, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(err.contains("not a lobelight bake cache"), "{err}");
}

/// A headless command's stderr holds only what lobelight says: no driver complaint about a
/// missing XDG_RUNTIME_DIR (Mesa prints one at every device open without it).
#[test]
fn headless_commands_print_no_driver_noise() {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lobelight"));
    cmd.args(["info", "scenes/cornell.toml", "--json"])
        .env_remove("XDG_RUNTIME_DIR");
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "stderr: {stderr}");
}

/// With no adapter at all (the Vulkan loader pointed at no driver), render and info run the
/// CPU mirror and say so in one line that names lavapipe; a backend asked for by name stays an
/// error.
#[test]
fn no_adapter_falls_back_to_the_cpu_mirror() {
    let hidden = [
        ("VK_ICD_FILENAMES", "/nonexistent/icd.json"),
        ("VK_DRIVER_FILES", "/nonexistent/icd.json"),
        ("WGPU_BACKEND", "vulkan"),
    ];
    let png = std::env::temp_dir()
        .join(format!("lobelight-nogpu-{}.png", std::process::id()))
        .display()
        .to_string();
    let render = [
        "render",
        "scenes/diffuse.toml",
        "--photons",
        "20000",
        "--width",
        "24",
        "--height",
        "24",
        "-o",
        &png,
    ];
    for args in [&["info", "scenes/cornell.toml"][..], &render[..]] {
        let out = lobelight(args, &hidden);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{args:?}: {err}");
        let said: Vec<&str> = err.lines().filter(|l| l.contains("CPU mirror")).collect();
        assert_eq!(said.len(), 1, "{args:?}: {err}");
        assert!(said[0].contains("lavapipe"), "{}", said[0]);
    }
    assert!(std::path::Path::new(&png).is_file());
    std::fs::remove_file(&png).ok();
    let named = lobelight(
        &["info", "scenes/cornell.toml", "--backend", "vulkan"],
        &hidden,
    );
    assert!(!named.status.success());
}

/// `render --views` draws a sequence from one bake, each view to its numbered file; `--shard
/// K/N` draws every N-th view from K, so the shards together draw each view once; `--shard
/// auto` takes K and N from a SLURM array or a Kubernetes Indexed Job.
#[test]
fn views_render_a_sequence_and_shards_split_it() {
    let dir = std::env::temp_dir().join(format!("lobelight-views-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let views = dir.join("views.toml");
    std::fs::write(&views, "[orbit]\nframes = 5\ndegrees = 40.0\n").unwrap();
    let out = |name: &str| dir.join(name).display().to_string();
    let (views_arg, cache) = (views.display().to_string(), out("bake.cache"));
    let run_in = |pattern: &str, shard: Option<&str>, env: &[(&str, &str)]| {
        let o = out(pattern);
        let mut args = vec![
            "render",
            "scenes/diffuse.toml",
            "--photons",
            "20000",
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "1",
            "--views",
            &views_arg,
            "--cache",
            &cache,
            "-o",
            &o,
            "--json",
        ];
        if let Some(s) = shard {
            args.extend(["--shard", s]);
        }
        lobelight(&args, env)
    };
    let run = |pattern: &str, shard: Option<&str>| run_in(pattern, shard, &[]);
    let all = run("all_##.png", None);
    assert!(
        all.status.success(),
        "{}",
        String::from_utf8_lossy(&all.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&all.stdout).unwrap();
    assert_eq!(report["views"].as_array().unwrap().len(), 5);
    for k in 0..5 {
        assert!(dir.join(format!("all_{k:02}.png")).is_file(), "view {k}");
    }
    let mut drawn = Vec::new();
    for shard in ["0/2", "1/2"] {
        let r = run("part_##.png", Some(shard));
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let report: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
        assert_eq!(report["cache_hit"], true, "shards share the bake");
        drawn.extend(
            report["views"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v["index"].as_u64().unwrap()),
        );
    }
    drawn.sort();
    assert_eq!(drawn, vec![0, 1, 2, 3, 4]);
    // The same view from a shard and from the whole run is the same image.
    let a = std::fs::read(dir.join("all_03.png")).unwrap();
    let b = std::fs::read(dir.join("part_03.png")).unwrap();
    assert_eq!(a, b);
    for bad in ["2/2", "1", "a/b"] {
        let r = run("bad_##.png", Some(bad));
        assert!(!r.status.success(), "--shard {bad} was accepted");
    }
    // `--shard auto` from a SLURM array (--array=1-3:2: tasks 1 and 3, the second here) and
    // from a Kubernetes Indexed Job (index 0 of 2).
    let slurm = [
        ("SLURM_ARRAY_TASK_ID", "3"),
        ("SLURM_ARRAY_TASK_MIN", "1"),
        ("SLURM_ARRAY_TASK_STEP", "2"),
        ("SLURM_ARRAY_TASK_COUNT", "2"),
    ];
    let k8s = [("JOB_COMPLETION_INDEX", "0"), ("LOBELIGHT_SHARDS", "2")];
    for (env, want) in [(&slurm[..], vec![1, 3]), (&k8s[..], vec![0, 2, 4])] {
        let r = run_in("auto_##.png", Some("auto"), env);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let report: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
        let drawn: Vec<u64> = (report["views"].as_array().unwrap().iter())
            .map(|v| v["index"].as_u64().unwrap())
            .collect();
        assert_eq!(drawn, want, "{env:?}");
    }
    let alone = run("auto_##.png", Some("auto"));
    let e = String::from_utf8_lossy(&alone.stderr);
    assert!(
        !alone.status.success() && e.contains("SLURM_ARRAY_TASK_ID"),
        "{e}"
    );
    let uncounted = run_in("auto_##.png", Some("auto"), &k8s[..1]);
    let e = String::from_utf8_lossy(&uncounted.stderr);
    assert!(
        !uncounted.status.success() && e.contains("LOBELIGHT_SHARDS"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `bench scale` on two small generated clouds: its JSON keys (a contract), one row per size in
/// ascending order with the splats it asked for, positive times, the frame ratio of the rows and
/// of frames in turn, and the clouds and scene files left in the output folder. A size of 0 is
/// a clear error.
#[test]
fn bench_scale_reports_each_size() {
    let dir = std::env::temp_dir().join("lobelight-bench-scale");
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.to_string_lossy().into_owned();
    let v = json(&[
        "bench",
        "scale",
        "--sizes",
        "4000,1000",
        "-o",
        &out,
        "--photons",
        "1000",
        "--json",
    ]);
    for key in ["adapter", "backend", "rows", "growth"] {
        assert!(v.get(key).is_some(), "missing key {key}: {v}");
    }
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for (row, n) in rows.iter().zip([1000, 4000]) {
        assert_eq!(row["splats"], n, "{row}");
        assert_eq!(row["photons"], 1000, "the bake options apply: {row}");
        for key in [
            "read_ms",
            "read_mb_per_s",
            "load_ms",
            "grid_ms",
            "photons_ms",
            "binning_ms",
            "em_ms",
            "direct_ms",
            "bake_ms",
            "frame_ms",
            "corner_frame_ms",
            "select_ms",
        ] {
            assert!(row[key].as_f64().is_some_and(|x| x > 0.0), "{key}: {row}");
        }
        // The passes of the frame: visibility (the selection in it), attributes, shade, and
        // no temporal pass.
        let passes: Vec<f64> = (row["passes_ms"].as_array().unwrap().iter())
            .map(|p| p.as_f64().unwrap_or(-1.0))
            .collect();
        assert!(
            passes.len() == 4 && passes[..3].iter().all(|&p| p > 0.0),
            "{row}"
        );
        assert_eq!(passes[3], 0.0, "{row}");
        assert!(
            row["select_ms"].as_f64().unwrap() <= 10.0 * passes[0],
            "{row}"
        );
        assert!(dir.join(format!("terrain_{n}.ply")).is_file());
        assert!(dir.join(format!("terrain_{n}.toml")).is_file());
    }
    for key in [
        "load",
        "grid",
        "bake",
        "frame",
        "frame_ratio",
        "frame_ratio_interleaved",
    ] {
        assert!(
            v["growth"][key].as_f64().is_some_and(f64::is_finite),
            "{key}: {v}"
        );
    }
    // Frames in turn: a ratio of two positive times.
    assert!(
        v["growth"]["frame_ratio_interleaved"]
            .as_f64()
            .unwrap_or(0.0)
            > 0.0,
        "{v}"
    );
    let (first, last) = (&rows[0]["frame_ms"], &rows[rows.len() - 1]["frame_ms"]);
    let ratio = last.as_f64().unwrap_or(0.0) / first.as_f64().unwrap_or(1.0);
    let said = v["growth"]["frame_ratio"].as_f64().unwrap_or(0.0);
    assert!(
        (said - ratio).abs() <= 1e-9 * ratio,
        "{said} against {ratio}"
    );
    assert_eq!(v["material"], "diffuse");
    assert!(rows.iter().all(|r| r["splats_fitted"] == 0), "{v}");
    // A glossy cloud fits lobes, most of its splats served by shared fits; its scene file
    // beside the diffuse one's, over the same points.
    let g = json(&[
        "bench",
        "scale",
        "--sizes",
        "4000",
        "--material",
        "glossy",
        "-o",
        &out,
        "--photons",
        "1000",
        "--json",
    ]);
    assert_eq!(g["material"], "glossy");
    // The bake runs where still images do: on the mirror beside a software rasterizer.
    let software = g["adapter"]
        .as_str()
        .is_some_and(|a| a.contains("llvmpipe"));
    let engine = if software { "mirror" } else { "device" };
    assert_eq!(g["bake_engine"], engine, "{g}");
    let row = &g["rows"][0];
    let (fitted, served) = (
        row["splats_fitted"].as_u64().unwrap(),
        row["splats_served"].as_u64().unwrap(),
    );
    assert!(fitted > 0 && served > fitted, "{row}");
    // One coverage measure a group, none for a splat a fit serves (it joins its leader's).
    let coverages = row["coverages"].as_u64().unwrap();
    assert!(coverages >= 1 && coverages + served <= 4000, "{row}");
    // Final gathering's direct bake is a part of the EM's time.
    let (em, direct) = (
        row["em_ms"].as_f64().unwrap(),
        row["em_direct_ms"].as_f64().unwrap(),
    );
    assert!(direct > 0.0 && direct < em, "{row}");
    assert!(g["growth"]["em_without_direct"].is_number(), "{g}");
    assert!(dir.join("terrain_4000_glossy.toml").is_file());
    let bad = lobelight(&["bench", "scale", "--sizes", "0", "-o", &out], &[]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("above 0"));
}

/// `bench cluster` writes the room with a block and the room with a dense cloud and bakes
/// both: the cloud's object holds the splats asked for and crowds the splat grid's cells more
/// than the block, both rates are positive, and the slowdowns are their ratios. No cloud is
/// a clear error.
#[test]
fn bench_cluster_reports_both_rooms() {
    let dir = std::env::temp_dir().join("lobelight-bench-cluster");
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.display().to_string();
    let v = json(&[
        "bench",
        "cluster",
        "--cluster-splats",
        "3000",
        "--photons",
        "4000",
        "--gather",
        "4",
        "-o",
        &out,
        "--json",
    ]);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2, "{v}");
    let (block, cloud) = (&rows[0], &rows[1]);
    assert_eq!(cloud["object_splats"], 3000, "{v}");
    assert!(
        cloud["max_cell_len"].as_u64() > block["max_cell_len"].as_u64(),
        "{v}"
    );
    let rate = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap();
    for r in rows {
        assert!(
            rate(r, "photons_per_s") > 0.0 && rate(r, "gather_rays_per_s") > 0.0,
            "{r}"
        );
        assert!(r["rays"].as_u64().unwrap() > 0, "{r}");
    }
    let ratio = rate(block, "photons_per_s") / rate(cloud, "photons_per_s");
    assert!(
        (rate(&v, "photons_slowdown") - ratio).abs() < 1e-9 * ratio,
        "{v}"
    );
    assert!(dir.join("cluster_3000.ply").is_file() && dir.join("cluster_block.toml").is_file());
    let bad = lobelight(
        &["bench", "cluster", "--cluster-splats", "0", "-o", &out],
        &[],
    );
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("at least one splat"));
}

/// `benches/gpu-check.sh`, the script a session lent a GPU runs, works on this device too: in
/// its quick sizes it writes one JSON with the adapter's name and every step's report, each
/// step run and passed.
#[test]
fn the_gpu_check_runs_here() {
    let out = std::env::temp_dir().join("lobelight-gpu-check.json");
    let _ = std::fs::remove_file(&out);
    let run = Command::new("bash")
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/benches/gpu-check.sh"))
        .args(["--quick", "--no-tests", "-o"])
        .arg(&out)
        .env("LOBELIGHT", env!("CARGO_BIN_EXE_lobelight"))
        .output()
        .expect("run benches/gpu-check.sh");
    let log = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "gpu-check failed:\n{log}");
    let text = std::fs::read_to_string(&out).expect("gpu-check wrote its JSON");
    let v: serde_json::Value = serde_json::from_str(&text).expect("gpu-check's JSON parses");
    let adapter = v["adapter"].as_str().unwrap_or_default();
    assert!(!adapter.is_empty(), "no adapter: {v}");
    let steps = v["steps"].as_object().expect("steps");
    let reports = [
        ("photons_cornell", "photons_per_s"),
        ("em_cornell", "fits_per_s"),
        ("frame_cornell", "frame_ms"),
        ("scale_diffuse", "growth"),
        ("scale_glossy", "growth"),
        ("cluster", "photons_slowdown"),
    ];
    for (step, key) in reports {
        let s = &steps[step];
        assert_eq!(s["status"], "ok", "{step}: {s}");
        assert_eq!(s["report"]["adapter"], adapter, "{step}: {s}");
        assert!(s["report"].get(key).is_some(), "{step} lacks {key}: {s}");
    }
    assert_eq!(steps.len(), reports.len(), "{:?}", steps.keys());
}

/// Where the only adapter is a software rasterizer, `render` runs the bake and the image on the
/// CPU mirror, which renders them faster, and says so in one line; `--gpu` and a backend named
/// with `--backend` run them on the adapter. On a GPU, `render` runs on it.
#[test]
fn render_runs_the_faster_engine_and_says_which() {
    let software = common::gpu().is_software();
    let png = std::env::temp_dir()
        .join(format!("lobelight-engine-{}.png", std::process::id()))
        .display()
        .to_string();
    let render = |extra: &[&str]| {
        let mut args = vec![
            "render",
            "scenes/diffuse.toml",
            "--photons",
            "20000",
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "1",
            "-o",
            &png,
            "--json",
        ];
        args.extend_from_slice(extra);
        let out = lobelight(&args, &[]);
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{extra:?}: {err}");
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("render's JSON");
        let backend = v["backend"].as_str().unwrap_or_default().to_string();
        // A device's render says what its pipelines' compile took; the mirror compiles none.
        let compiled = v["pipelines"]["pipelines"].as_u64();
        if backend == "cpu" {
            assert_eq!(compiled, None, "{v}");
        } else {
            assert!(compiled.is_some_and(|n| n > 0), "{v}");
            assert!(
                v["pipelines"]["ms"].as_f64().is_some_and(|ms| ms > 0.0),
                "{v}"
            );
        }
        (backend, err)
    };
    let (backend, err) = render(&[]);
    let said: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("software rasterizer"))
        .collect();
    if software {
        assert_eq!(backend, "cpu", "{err}");
        assert_eq!(said.len(), 1, "{err}");
        assert!(
            said[0].contains("CPU mirror") && said[0].contains("--gpu"),
            "{err}"
        );
    } else {
        assert_ne!(backend, "cpu", "{err}");
        assert!(said.is_empty(), "{err}");
    }
    for forced in [&["--gpu"][..], &["--backend", "vulkan"][..]] {
        let (backend, err) = render(forced);
        assert_ne!(backend, "cpu", "{forced:?}: {err}");
        assert!(!err.contains("software rasterizer"), "{forced:?}: {err}");
    }
    assert_eq!(render(&["--cpu"]).0, "cpu");
    let both = lobelight(
        &[
            "render",
            "scenes/diffuse.toml",
            "--cpu",
            "--gpu",
            "-o",
            &png,
        ],
        &[],
    );
    assert!(!both.status.success(), "--cpu with --gpu is refused");
    std::fs::remove_file(&png).ok();
}
