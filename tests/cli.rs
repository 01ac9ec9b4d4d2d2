//! The `lobelight` binary: `info` on the shipped scenes, its JSON keys (a contract), the GL
//! fallback, and one-line errors with a non-zero exit.

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
