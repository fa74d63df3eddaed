//! The binary as a user runs it: device listing and the errors when no device fits.

use std::process::{Command, Output};

fn translucent(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_translucent"));
    cmd.args(args)
        .env("TRANSLUCENT_VALIDATION", "1")
        .env_remove("TRANSLUCENT_DEVICE");
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("run translucent")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn assert_clean_failure(out: &Output) -> String {
    let stderr = text(&out.stderr);
    assert!(
        !out.status.success(),
        "expected failure, got success; stdout: {}",
        text(&out.stdout)
    );
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(
        !stderr.contains("panicked"),
        "panic instead of an error: {stderr}"
    );
    stderr
}

#[test]
fn devices_lists_llvmpipe() {
    let out = translucent(&["devices"], &[]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "stderr: {}", text(&out.stderr));
    assert!(
        stdout.contains("llvmpipe"),
        "no llvmpipe (lavapipe) device; run `bash scripts/setup` to install mesa-vulkan-drivers.\n{stdout}"
    );
    let json = translucent(&["devices", "--json"], &[]);
    let parsed: serde_json::Value =
        serde_json::from_slice(&json.stdout).expect("devices --json is JSON");
    assert!(
        parsed
            .as_array()
            .is_some_and(|a| a.iter().any(|d| d["driver"] == "llvmpipe")),
        "{parsed}"
    );
}

#[test]
fn smoke_render_runs_clean_under_validation() {
    let out = translucent(&["render", "--count", "4096"], &[]);
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "stderr: {stderr}");
    assert!(!stderr.contains("[vulkan"), "validation messages: {stderr}");
    assert!(
        text(&out.stdout).contains("4096 values correct"),
        "{}",
        text(&out.stdout)
    );
}

#[test]
fn unknown_device_lists_the_devices() {
    let out = translucent(&["--device", "no-such-gpu-xyz", "render"], &[]);
    let stderr = assert_clean_failure(&out);
    assert!(
        stderr.contains("no-such-gpu-xyz") && stderr.contains("llvmpipe"),
        "{stderr}"
    );
    let out = translucent(&["render"], &[("TRANSLUCENT_DEVICE", "99")]);
    let stderr = assert_clean_failure(&out);
    assert!(
        stderr.contains("\"99\"") && stderr.contains("available devices"),
        "{stderr}"
    );
}

#[test]
fn no_vulkan_driver_says_what_to_install() {
    // Point the loader at a driver manifest that does not exist: the state of a machine
    // without mesa-vulkan-drivers.
    let env = [
        ("VK_ICD_FILENAMES", "/nonexistent/icd.json"),
        ("VK_DRIVER_FILES", "/nonexistent/icd.json"),
    ];
    for args in [&["devices"][..], &["render"][..]] {
        let out = translucent(args, &env);
        let stderr = assert_clean_failure(&out);
        assert!(stderr.contains("mesa-vulkan-drivers"), "{args:?}: {stderr}");
    }
}

#[test]
fn help_is_everywhere() {
    for args in [
        &["--help"][..],
        &["devices", "--help"],
        &["render", "--help"],
        &["material", "--help"],
        &["sample", "--help"],
    ] {
        let out = translucent(args, &[]);
        assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
        assert!(text(&out.stdout).contains("Usage"), "{args:?}");
    }
}
