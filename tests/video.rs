//! `render --views FILE -o NAME.mp4`: a camera path's frames as one H.264 video, decoded by
//! Debian's ffmpeg (a test tool only; lobelight encodes in the process): its frame count, size
//! and rate, and a frame against the PNG of the same view.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

// A small lit room, few photons: the frames differ by their views alone.
const SCENE: &str = r#"
[camera]
eye = [0.0, 0.0, 3.9]
target = [0.0, 0.0, 0.0]
fov = 39.3
resolution = [96, 64]

[bake]
photons = 60000

[materials.white]
diffuse = [0.8, 0.8, 0.8]

[materials.red]
diffuse = [0.6, 0.05, 0.05]

[[light]]
type = "area"
center = [0.0, 0.99, 0.0]
size = [0.5, 0.5]
normal = [0.0, -1.0, 0.0]
u_axis = [1.0, 0.0, 0.0]
radiance = [12.0, 12.0, 12.0]

[[object]]
shape = "cornell_box"
material = "white"
left_material = "red"
right_material = "white"
spacing = 0.05

[[object]]
shape = "box"
scale = 0.3
rotate = [0.0, 20.0, 0.0]
translate = [0.2, -0.7, 0.1]
material = "white"
spacing = 0.04
"#;

// 1.5 s at 8 frames a second: 13 frames through three keys.
const PATH: &str = r#"
[path]
fps = 8
[[path.key]]
time = 0.0
[[path.key]]
time = 1.0
eye = [1.2, 0.3, 3.5]
target = [0.0, -0.3, 0.0]
[[path.key]]
time = 1.5
eye = [-1.0, -0.2, 3.6]
fov = 45.0
"#;

/// The least PSNR of a decoded frame against the PNG of its view. H.264 at OpenH264's fixed
/// quantizer, BT.601 studio range and 4:2:0 chroma (which halves the box's red edge): 32–34 dB
/// measured on this scene at 128 × 128.
const MIN_PSNR: f64 = 30.0;

fn lobelight(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lobelight"))
        .args(args)
        .output()
        .expect("run lobelight")
}

fn ok(out: Output, what: &str) -> Output {
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Debian's ffmpeg and ffprobe, which the tests need (`.ci/run` installs them).
fn tool(name: &str, args: &[&str]) -> Output {
    match Command::new(name).args(args).output() {
        Ok(out) => out,
        Err(e) => panic!(
            "{name} is needed to decode the video in this test (apt-get install ffmpeg): {e}"
        ),
    }
}

/// What ffprobe reads of a video's first stream: its codec, size, rate and frames decoded.
fn video_stream(video: &Path) -> serde_json::Value {
    let fields = "stream=codec_name,width,height,r_frame_rate,nb_read_frames";
    let args = [
        "-v",
        "error",
        "-select_streams",
        "v:0",
        "-count_frames",
        "-show_entries",
    ];
    let probe = tool(
        "ffprobe",
        &[&args[..], &[fields, "-of", "json", s(video)]].concat(),
    );
    let probe: serde_json::Value = serde_json::from_slice(&ok(probe, "ffprobe").stdout).unwrap();
    probe["streams"][0].clone()
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lobelight-video-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("scene.toml"), SCENE).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

fn psnr(a: &image::RgbImage, b: &image::RgbImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let n = a.as_raw().len() as f64;
    let mse: f64 = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(&x, &y)| (x as f64 - y as f64).powi(2))
        .sum::<f64>()
        / n;
    10.0 * (255.0f64 * 255.0 / mse.max(1e-12)).log10()
}

#[test]
fn a_camera_path_becomes_a_video_whose_frames_are_its_views() {
    let d = dir("path");
    std::fs::write(d.join("path.toml"), PATH).unwrap();
    let (scene, path) = (d.join("scene.toml"), d.join("path.toml"));
    let cache = d.join("scene.bake");
    let video = d.join("fly.mp4");
    let common = [
        "--cpu",
        "--spp",
        "2",
        "--cache",
        s(&cache),
        "--views",
        s(&path),
    ];
    let out = ok(
        lobelight(
            &[
                &["render", s(&scene), "-o", s(&video), "--json"][..],
                &common,
            ]
            .concat(),
        ),
        "the video",
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["video"]["frames"], 13);
    assert_eq!(report["video"]["fps"], 8.0);

    let stream = video_stream(&video);
    assert_eq!(stream["codec_name"], "h264");
    assert_eq!(
        (stream["width"].as_u64(), stream["height"].as_u64()),
        (Some(96), Some(64))
    );
    assert_eq!(stream["r_frame_rate"], "8/1");
    assert_eq!(stream["nb_read_frames"], "13");

    // The same views as numbered PNGs, from the same bake; frames 0, 6 and 12 decoded.
    let frames = d.join("frame_####.png");
    ok(
        lobelight(&[&["render", s(&scene), "-o", s(&frames)][..], &common].concat()),
        "frames",
    );
    for k in [0, 6, 12] {
        let decoded = d.join(format!("decoded_{k}.png"));
        let select = format!("select=eq(n\\,{k})");
        let args = [
            "-v",
            "error",
            "-y",
            "-i",
            s(&video),
            "-vf",
            &select,
            "-vframes",
            "1",
        ];
        ok(
            tool("ffmpeg", &[&args[..], &[s(&decoded)]].concat()),
            "ffmpeg",
        );
        let png = d.join(format!("frame_{k:04}.png"));
        let db = psnr(&rgb(&decoded), &rgb(&png));
        assert!(db >= MIN_PSNR, "frame {k}: {db:.1} dB against its PNG");
    }
    // Frames of different views differ more than a frame from its own view.
    let far = psnr(
        &rgb(&d.join("frame_0000.png")),
        &rgb(&d.join("decoded_12.png")),
    );
    assert!(far < MIN_PSNR, "frames 0 and 12 alike: {far:.1} dB");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_nerfstudio_camera_path_sets_the_frames_and_their_rate() {
    let d = dir("nerfstudio");
    // Three cameras 0.4 apart along x, looking along −z, at 5 frames a second.
    let camera = |x: f32| {
        format!(
            r#"{{"camera_to_world": [1, 0, 0, {x}, 0, 1, 0, 0, 0, 0, 1, 3.9, 0, 0, 0, 1], "fov": 40, "aspect": 1.5}}"#
        )
    };
    let json = format!(
        r#"{{"render_width": 96, "render_height": 64, "fps": 5, "seconds": 0.6,
            "camera_path": [{}, {}, {}]}}"#,
        camera(-0.4),
        camera(0.0),
        camera(0.4)
    );
    std::fs::write(d.join("path.json"), json).unwrap();
    let video = d.join("ns.mp4");
    let (scene, path) = (d.join("scene.toml"), d.join("path.json"));
    let args = ["render", s(&scene), "-o", s(&video), "--cpu", "--spp", "1"];
    let out = lobelight(&[&args[..], &["--views", s(&path), "--json"]].concat());
    let report: serde_json::Value = serde_json::from_slice(&ok(out, "render").stdout).unwrap();
    assert_eq!(report["video"]["frames"], 3);
    assert_eq!(report["video"]["fps"], 5.0);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn what_a_video_cannot_be_is_one_line() {
    let d = dir("errors");
    std::fs::write(d.join("path.toml"), PATH).unwrap();
    let (scene, path) = (d.join("scene.toml"), d.join("path.toml"));
    let video = d.join("v.mp4");
    for (extra, expect) in [
        (vec![], "a video is a sequence"),
        (
            vec!["--views", s(&path), "--width", "95"],
            "even width and height",
        ),
        (vec!["--views", s(&path), "--shard", "0/2"], "--shard"),
        (vec!["--views", s(&path), "--fps", "0"], "fps"),
    ] {
        let args = [
            &["render", s(&scene), "-o", s(&video), "--cpu", "--spp", "1"][..],
            &extra,
        ]
        .concat();
        let out = lobelight(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{extra:?} succeeded");
        assert!(err.contains(expect), "{extra:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{extra:?}: {err}");
    }
    std::fs::remove_dir_all(&d).ok();
}

/// The decoded frames' checksums (ffmpeg's framemd5), one line a frame.
fn frame_md5s(video: &Path) -> Vec<String> {
    let out = tool(
        "ffmpeg",
        &["-v", "error", "-i", s(video), "-f", "framemd5", "-"],
    );
    let text = String::from_utf8(ok(out, "ffmpeg framemd5").stdout).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.rsplit(',').next().unwrap_or("").trim().to_string())
        .collect()
}

#[test]
fn shards_started_by_a_scheduler_join_into_one_process_s_video() {
    let d = dir("shards");
    std::fs::write(d.join("path.toml"), PATH).unwrap();
    let (scene, path) = (d.join("scene.toml"), d.join("path.toml"));
    let cache = d.join("scene.bake");
    let common = [
        "--cpu",
        "--spp",
        "1",
        "--cache",
        s(&cache),
        "--views",
        s(&path),
    ];
    // One process: the whole path as a video (and the bake the shards share).
    let one = d.join("one.mp4");
    ok(
        lobelight(&[&["render", s(&scene), "-o", s(&one)][..], &common].concat()),
        "one",
    );
    // Three SLURM array tasks, then three Kubernetes Indexed Job pods, each its share.
    // A scheduler's environment of task k.
    type Env = fn(u32) -> Vec<(String, String)>;
    let schedulers: [(&str, Env); 2] = [
        ("slurm", |k| {
            vec![
                ("SLURM_ARRAY_TASK_ID".into(), k.to_string()),
                ("SLURM_ARRAY_TASK_COUNT".into(), "3".into()),
                ("SLURM_ARRAY_TASK_MIN".into(), "0".into()),
                ("SLURM_ARRAY_TASK_STEP".into(), "1".into()),
            ]
        }),
        ("k8s", |k| {
            vec![
                ("JOB_COMPLETION_INDEX".into(), k.to_string()),
                ("LOBELIGHT_SHARDS".into(), "3".into()),
            ]
        }),
    ];
    for (name, env) in schedulers {
        let frames = d.join(format!("{name}_####.png"));
        for k in 0..3 {
            let args = [
                &["render", s(&scene), "-o", s(&frames), "--shard", "auto"][..],
                &common,
            ];
            let out = Command::new(env!("CARGO_BIN_EXE_lobelight"))
                .args(args.concat())
                .envs(env(k))
                .output()
                .unwrap();
            ok(out, &format!("{name} shard {k}"));
        }
        let joined = d.join(format!("{name}.mp4"));
        let out = lobelight(&["join", s(&frames), "-o", s(&joined), "--fps", "8"]);
        ok(out, "join");
        let (theirs, ours) = (frame_md5s(&joined), frame_md5s(&one));
        assert_eq!(ours.len(), 13);
        assert_eq!(
            theirs, ours,
            "{name}: the joined video's frames differ from one process's"
        );
    }
    // A missing frame is named.
    std::fs::remove_file(d.join("slurm_0005.png")).unwrap();
    let out = lobelight(&[
        "join",
        s(&d.join("slurm_####.png")),
        "-o",
        s(&d.join("x.mp4")),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("frame 5"), "{err}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn the_video_example_runs() {
    let d = dir("example");
    let video = d.join("fly.mp4");
    let out = Command::new("sh")
        .args(["examples/video.sh", "64", s(&video)])
        .env("LOBELIGHT", env!("CARGO_BIN_EXE_lobelight"))
        .output()
        .unwrap();
    ok(out, "examples/video.sh");
    let stream = video_stream(&video);
    assert_eq!(
        (stream["width"].as_u64(), stream["height"].as_u64()),
        (Some(64), Some(64))
    );
    assert_eq!(stream["r_frame_rate"], "30/1");
    // 0 s to 4 s at 30 a second, both ends in.
    assert_eq!(stream["nb_read_frames"], "121");
    std::fs::remove_dir_all(&d).ok();
}
