//! The memory budget: what a scene makes is counted before it is made, and past the budget the
//! scene is refused in one line that names the object, the estimate and the budget, with a
//! spacing that fits — never an abort, under an address-space limit too.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

use lobelight::budget::{Budget, SPLAT_BYTES, Source, parse_size};

const HEAD: &str = "[camera]\neye = [0, 0, 3]\ntarget = [0, 0, 0]\n\n[[light]]\ntype = \
                    \"point\"\nposition = [0, 0, 2]\npower = 10\n";

fn dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lobelight-budget-{name}"));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `lobelight info SCENE --cpu ARGS` under `ulimit -v` (KiB): exit status and stderr.
fn info(scene: &Path, args: &str, ulimit_kib: u64) -> (Option<i32>, String) {
    let exe = env!("CARGO_BIN_EXE_lobelight");
    let script = format!(
        "ulimit -v {ulimit_kib}; exec \"{exe}\" info \"{}\" --cpu {args}",
        scene.display()
    );
    let out = Command::new("bash").arg("-c").arg(script).output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn sizes_parse_in_the_units_people_write() {
    assert_eq!(parse_size("1000"), Ok(1000));
    assert_eq!(parse_size("8G"), Ok(8 << 30));
    assert_eq!(parse_size("512MiB"), Ok(512 << 20));
    assert_eq!(parse_size("64 mb"), Ok(64 << 20));
    assert_eq!(parse_size("1.5g"), Ok(3 << 29));
    for bad in ["8X", "", "G", "0", "-1G", "1e400"] {
        let e = parse_size(bad).unwrap_err();
        assert!(e.contains(&format!("`{bad}`")), "{bad}: {e}");
    }
}

/// A sphere too fine for the scene's `max_memory` is refused at its line, and the spacing the
/// error suggests loads within the budget.
#[test]
fn a_shape_past_the_budget_is_refused_with_a_spacing_that_fits() {
    let budget = 64u64 << 20;
    let scene = |spacing: &str| {
        format!(
            "max_memory = \"64M\"\n{HEAD}\n[[object]]\nshape = \"sphere\"\nradius = 1.0\n\
             spacing = {spacing}\n"
        )
    };
    let path = Path::new("fine.toml");
    let e = lobelight::scene::parse(path, &scene("0.002"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("fine.toml: line 11: object #1 (sphere)"), "{e}");
    assert!(
        e.contains("past the budget of 64.0 MiB (the scene's max_memory)"),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1, "{e}");
    let suggested = e
        .split("raise `spacing` to ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .unwrap_or_else(|| panic!("no spacing in: {e}"));
    let fits = lobelight::scene::parse(path, &scene(suggested)).unwrap();
    let bytes = fits.splats.len() as u64 * SPLAT_BYTES;
    assert!(
        bytes <= budget,
        "{} splats at {suggested}",
        fits.splats.len()
    );
    // Within the 1 % the search stops at: a spacing 2 % finer is past the budget.
    let finer = suggested.parse::<f32>().unwrap() * 0.98;
    assert!(lobelight::scene::parse(path, &scene(&finer.to_string())).is_err());
}

/// The worst cases of a model surface, under a 4 GiB address-space limit: one triangle repeated
/// 20,000 times at a fine spacing, and one triangle at spacing 1e-9 (16.8 M splats). Each gets
/// the budget's one-line error in well under a second, not an abort.
#[test]
fn surfaces_past_the_budget_fail_cleanly_under_an_address_space_limit() {
    let dir = dir("surfaces");
    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    std::fs::write(dir.join("one.obj"), format!("{triangle}f 1 2 3\n")).unwrap();
    std::fs::write(
        dir.join("repeated.obj"),
        format!("{triangle}{}", "f 1 2 3\n".repeat(20_000)),
    )
    .unwrap();
    for (model, spacing) in [("repeated.obj", "0.0002"), ("one.obj", "1e-9")] {
        let scene = dir.join(format!("{model}.toml"));
        let text = format!(
            "{HEAD}\n[[object]]\nshape = \"model\"\npath = \"{model}\"\nspacing = {spacing}\n"
        );
        std::fs::write(&scene, text).unwrap();
        let started = std::time::Instant::now();
        let (code, stderr) = info(&scene, "", 4 << 20);
        assert_eq!(code, Some(1), "{model}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains("past the budget of"), "{stderr}");
        assert!(stderr.contains("raise `spacing` to"), "{stderr}");
        assert!(
            started.elapsed().as_secs_f64() < 5.0,
            "{model}: counted, not made"
        );
    }
}

/// A gzip file that inflates past a quarter of the budget is refused, not cut short; the
/// command line's budget wins over the scene's.
#[test]
fn a_gzip_bomb_is_refused_and_the_flag_wins_over_the_scene() {
    let dir = dir("gzip");
    let gz = dir.join("bomb.xyz.gz");
    let mut enc = flate2::write::GzEncoder::new(
        std::fs::File::create(&gz).unwrap(),
        flate2::Compression::best(),
    );
    let lines = "0 0 0\n".repeat(1 << 20);
    for _ in 0..8 {
        enc.write_all(lines.as_bytes()).unwrap(); // 48 MiB inflated
    }
    enc.finish().unwrap();
    let scene = dir.join("bomb.toml");
    let text = format!(
        "max_memory = \"1G\"\n{HEAD}\n[[object]]\nshape = \"model\"\npath = \"bomb.xyz.gz\"\n"
    );
    std::fs::write(&scene, text).unwrap();
    let (code, stderr) = info(&scene, "--max-memory 64M", 4 << 20);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("bomb.xyz.gz: gzip: it inflates to more than 16.0 MiB"),
        "{stderr}"
    );
    assert!(stderr.contains("of 64.0 MiB"), "{stderr}");
}

/// A scene's budget is in force over the machine's share (the flag's over both: above).
#[test]
fn a_scene_budget_wins_over_the_machine_share() {
    let machine = Budget::current();
    assert_eq!(machine.source, Source::Machine);
    assert!(machine.bytes >= 1 << 20);
    let scene = Budget::for_scene(Some(64 << 20));
    assert_eq!((scene.bytes, scene.source), (64 << 20, Source::Scene));
}

/// A bake whose photons would store past the budget is refused after its first batch, with the
/// photon count that fits, and that count bakes.
#[test]
fn photons_past_the_budget_are_refused_after_the_first_batch() {
    use lobelight::photons::PhotonConfig;
    use lobelight::renderer::{Engine, Renderer};
    let scene = lobelight::scene::load(Path::new("scenes/cornell.toml")).unwrap();
    let budget = Budget {
        bytes: 4 << 20,
        source: Source::Flag,
    };
    let cfg = PhotonConfig {
        photons: 4_000_000_000,
        batch: 8192,
        memory: budget,
        ..PhotonConfig::from_scene(&scene)
    };
    let renderer = Renderer::new(std::sync::Arc::new(scene), &Engine::Mirror).unwrap();
    let t = std::time::Instant::now();
    let Err(e) = renderer.trace_photons(&cfg, &mut |_, _| {}) else {
        panic!("4 G photons traced within 4 MiB");
    };
    let e = e.to_string();
    assert!(e.contains("past the budget of 4.0 MiB"), "{e}");
    assert!(t.elapsed().as_secs() < 30, "{:?}", t.elapsed());
    let fits: u64 = e
        .split("lower `photons` to ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no count in {e}"));
    let cfg = PhotonConfig {
        photons: fits * 9 / 10,
        ..cfg
    };
    let traced = renderer.trace_photons(&cfg, &mut |_, _| {}).unwrap();
    let bytes = traced.map.photons.len() as u64 * lobelight::photons::STORED_PHOTON_BYTES;
    assert!(bytes <= budget.bytes, "{bytes}");
}

/// A still image on the CPU mirror past the budget is refused before the bake, with the size
/// that fits.
#[test]
fn an_image_past_the_budget_is_refused_before_the_bake() {
    let exe = env!("CARGO_BIN_EXE_lobelight");
    let out = dir("image").join("huge.png");
    let t = std::time::Instant::now();
    let run = Command::new(exe)
        .args([
            "render",
            "scenes/cornell.toml",
            "--cpu",
            "--max-memory",
            "1G",
        ])
        .args(["--width", "16384", "--height", "8192", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("a 16384×8192 image on the CPU mirror"),
        "{stderr}"
    );
    assert!(stderr.contains("render at 3344×1672 or less"), "{stderr}");
    assert!(t.elapsed().as_secs() < 20, "{:?}", t.elapsed());
}

/// A model file larger than the budget is refused before a byte is read (a reader holds the
/// file whole).
#[test]
fn a_file_past_the_budget_is_not_read() {
    use lobelight::scene::model::{self, Reading};
    let path = dir("file").join("huge.xyz");
    let file = std::fs::File::create(&path).unwrap();
    // Sparse: 2 GiB that take no disk.
    file.set_len(2 << 30).unwrap();
    let reading = Reading::within(Budget {
        bytes: 1 << 30,
        source: Source::Flag,
    });
    let t = std::time::Instant::now();
    let e = model::load_with(&path, &reading).unwrap_err().to_string();
    assert!(
        e.contains("huge.xyz: size: the file would take about 2.0 GiB"),
        "{e}"
    );
    assert!(t.elapsed().as_millis() < 1000, "{:?}", t.elapsed());
    std::fs::remove_file(&path).ok();
}
