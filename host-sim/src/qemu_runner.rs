//! Run the firmware's QEMU image on a sensor log and decode what it streams.
//!
//! The firmware (`firmware/`, its own cargo workspace) has a QEMU `mps2-an386` image,
//! `ssvr-qemu`, that replays a binary sensor log (`firmware/LOG_FORMAT.md`) through its reversal
//! detector and the f32 estimator and streams defmt frames over semihosting (QEMU's stdout). The
//! image is built for a scene (`SSVR_SCENE`): structure, rate and detector settings are compiled
//! in, and the log header must match them. This module:
//!
//! * [`write_sensor_log`] / [`encode_sensor_log`]: write a log (format version 1);
//! * [`firmware_scene_toml`], [`build_for_scene`], [`build_for_scene_model`]: build an image for
//!   a [`Scene`] and an estimator model (`cargo build --release` in `firmware/` with
//!   `SSVR_SCENE` naming a file with the scene's firmware parameters and `SSVR_MODEL` the model,
//!   the parent cargo's target/flags environment removed, serialised by a file lock) and copy the
//!   ELF out; [`build_qemu_image`]: the same for the image's default scene and model;
//! * [`run_qemu`]: run the ELF under `qemu-system-arm -icount shift=0` with the log, return the
//!   raw defmt bytes;
//! * [`decode_frames`]: decode them with `defmt-decoder` (the firmware uses defmt 1.x, wire
//!   format version 4, which `defmt-decoder` 1.x reads) into [`DecodedFrame`]s;
//! * [`DecodedFrame::sample`], [`instruction_counts`]: the per-sample frames and the
//!   instruction counts the image measures at the end;
//! * [`elf_sizes`]: flash and RAM use of an image.
//!
//! Plain functions, no global state; errors are [`anyhow::Error`]s with context.

use crate::model::Model;
use crate::scene::Scene;
use anyhow::{anyhow, bail, Context, Result};
use ssvr_core::StructureParams;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Log file magic.
pub const LOG_MAGIC: [u8; 8] = *b"SSVRLOG1";
/// Log format version written by [`encode_sensor_log`].
pub const LOG_VERSION: u16 = 1;
/// Length of the version-1 header.
pub const LOG_HEADER_LEN: u16 = 80;
/// Channels per record.
pub const LOG_CHANNELS: u16 = 4;
/// Record flag: a channel was at the ADC full scale.
pub const RECORD_SATURATED: u8 = 1 << 0;
/// Record flag: the sample was not acquired.
pub const RECORD_MISSING: u8 = 1 << 1;
/// Record flag: the displacement channel was at its full scale (the detector skips it).
pub const RECORD_DISP_SATURATED: u8 = 1 << 2;
/// Header option (offset 14): test hook, the firmware takes friction events from the records'
/// reversal events instead of its detector.
pub const OPTION_LOG_REVERSALS: u16 = 1 << 0;
/// Record flag: a reversal event follows the flags byte.
pub const RECORD_HAS_REVERSAL: u8 = 1 << 7;

/// Bits of the `flags` field of the firmware's `sample` frames.
pub mod frame_flags {
    /// A channel is NaN or infinite.
    pub const NOT_FINITE: u8 = 1 << 0;
    /// A channel is at the ADC full scale.
    pub const SATURATED: u8 = 1 << 1;
    /// The sample is missing.
    pub const MISSING: u8 = 1 << 2;
    /// Frames were dropped before this one (streaming queue full).
    pub const OVERRUN: u8 = 1 << 3;
    /// A reversal was pushed to the estimator at this sample.
    pub const REVERSAL: u8 = 1 << 4;
    /// The estimator rejected a reversal at this sample.
    pub const REVERSAL_REJECTED: u8 = 1 << 5;
    /// The ADC reported an error (board image).
    pub const ADC_ERROR: u8 = 1 << 6;
    /// The displacement was unusable (missing, not finite, saturated); the detector repeated its
    /// last value.
    pub const DISP_INVALID: u8 = 1 << 7;
}

/// Kinds of friction events in the firmware's frames (`ev=`).
pub mod event_kind {
    /// The base started to slide (pushed to the estimator, fixed-base model: not).
    pub const SLIP_START: u8 = 1;
    /// The sliding direction reversed (pushed, fixed-base model: not).
    pub const REVERSAL: u8 = 2;
    /// The base stuck (pushed by the stick-slip model only).
    pub const STICK: u8 = 3;
    /// A reversal event of the log (test hook; pushed).
    pub const LOG: u8 = 4;
}

/// The name of the firmware's board binary.
pub const BOARD_BIN: &str = "ssvr-board";

/// The name of the firmware's QEMU binary.
pub const QEMU_BIN: &str = "ssvr-qemu";

/// The log header: the scene's sample rate and structure (the image checks them against its
/// compiled-in scene) and options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogHeader {
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Structure parameters (m1, m2, natural frequency, ξ, μ, g).
    pub params: StructureParams,
    /// Bits `OPTION_*` (0: the firmware's detector supplies the friction events).
    pub options: u16,
}

impl LogHeader {
    /// The header of a scene's log (no options).
    pub fn for_scene(scene: &Scene) -> Self {
        Self {
            sample_rate_hz: scene.rate_hz,
            params: *scene.structure.params(),
            options: 0,
        }
    }
}

/// A friction reversal carried by a record (used by the firmware only with
/// [`OPTION_LOG_REVERSALS`], a test hook; the firmware's detector is the default).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogReversal {
    /// New friction level: +1 or −1 (0 allowed).
    pub level: i8,
    /// Sample intervals between the reversal and this record's sample (≥ 0).
    pub age_samples: f32,
}

/// One sensor-log record.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LogSample {
    /// Table acceleration (m/s²).
    pub table_accel_m_s2: f32,
    /// Sliding-base acceleration (m/s²).
    pub base_accel_m_s2: f32,
    /// Top-mass acceleration (m/s²).
    pub top_accel_m_s2: f32,
    /// Base-to-table displacement (m).
    pub displacement_m: f32,
    /// A channel was at the ADC full scale.
    pub saturated: bool,
    /// The sample was not acquired (channels meaningless).
    pub missing: bool,
    /// The displacement channel was at its full scale (implies `saturated` in the log).
    pub disp_saturated: bool,
    /// A reversal reported with this sample.
    pub reversal: Option<LogReversal>,
}

/// Encode a sensor log (format version 1, little-endian; see `firmware/LOG_FORMAT.md`).
pub fn encode_sensor_log(header: &LogHeader, samples: &[LogSample]) -> Result<Vec<u8>> {
    let count = u32::try_from(samples.len())
        .ok()
        .filter(|&n| n != u32::MAX)
        .ok_or_else(|| anyhow!("too many samples for one log: {}", samples.len()))?;
    let mut b = Vec::with_capacity(80 + samples.len() * 22);
    b.extend_from_slice(&LOG_MAGIC);
    b.extend_from_slice(&LOG_VERSION.to_le_bytes());
    b.extend_from_slice(&LOG_HEADER_LEN.to_le_bytes());
    b.extend_from_slice(&LOG_CHANNELS.to_le_bytes());
    b.extend_from_slice(&header.options.to_le_bytes());
    let p = &header.params;
    for v in [
        header.sample_rate_hz,
        p.m1_kg,
        p.m2_kg,
        p.natural_frequency_hz,
        p.damping_ratio,
        p.friction_coefficient,
        p.gravity_m_s2,
    ] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.extend_from_slice(&count.to_le_bytes());
    b.extend_from_slice(&0u32.to_le_bytes());
    debug_assert_eq!(b.len(), usize::from(LOG_HEADER_LEN));
    for s in samples {
        for v in [
            s.table_accel_m_s2,
            s.base_accel_m_s2,
            s.top_accel_m_s2,
            s.displacement_m,
        ] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let mut flags = 0u8;
        if s.saturated || s.disp_saturated {
            flags |= RECORD_SATURATED;
        }
        if s.disp_saturated {
            flags |= RECORD_DISP_SATURATED;
        }
        if s.missing {
            flags |= RECORD_MISSING;
        }
        if s.reversal.is_some() {
            flags |= RECORD_HAS_REVERSAL;
        }
        b.push(flags);
        if let Some(r) = s.reversal {
            b.push(r.level as u8);
            b.extend_from_slice(&r.age_samples.to_le_bytes());
        }
    }
    Ok(b)
}

/// Write a sensor log to `path` (see [`encode_sensor_log`]).
pub fn write_sensor_log(path: &Path, header: &LogHeader, samples: &[LogSample]) -> Result<()> {
    let bytes = encode_sensor_log(header, samples)?;
    std::fs::write(path, bytes)
        .with_context(|| format!("cannot write the sensor log {}", path.display()))
}

/// `firmware/` next to this crate (`host-sim/../firmware`).
pub fn default_firmware_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("firmware")
}

/// Environment variables a parent cargo (e.g. `cargo test`) sets or honours that must not leak
/// into the firmware build: target dir, target triple, flags, per-package metadata.
fn leaks_into_nested_cargo(key: &str) -> bool {
    const EXACT: &[&str] = &[
        "CARGO_TARGET_DIR",
        "CARGO_BUILD_TARGET",
        "CARGO_BUILD_TARGET_DIR",
        "CARGO_BUILD_RUSTFLAGS",
        "CARGO_ENCODED_RUSTFLAGS",
        "RUSTFLAGS",
        "RUSTDOCFLAGS",
        "CARGO_MAKEFLAGS",
        "CARGO_PRIMARY_PACKAGE",
        "CARGO_CRATE_NAME",
        "CARGO_MANIFEST_DIR",
        "CARGO_MANIFEST_PATH",
        "DEFMT_LOG",
        "SSVR_QEMU_LOG",
        "SSVR_MODEL",
    ];
    const PREFIX: &[&str] = &[
        "CARGO_PKG_",
        "CARGO_BIN_",
        "CARGO_CFG_",
        "CARGO_FEATURE_",
        "CARGO_PROFILE_",
        "CARGO_TARGET_",
        "CARGO_LLVM_COV",
    ];
    EXACT.contains(&key) || PREFIX.iter().any(|p| key.starts_with(p))
}

/// Build the QEMU image for its default scene: `cargo build --release --bin ssvr-qemu` in
/// `firmware_dir` (see [`cargo_build`]). Returns the ELF (in `firmware/target`: a later build
/// for another scene overwrites it; [`build_for_scene`] copies it out).
pub fn build_qemu_image(firmware_dir: &Path) -> Result<PathBuf> {
    cargo_build(firmware_dir, QEMU_BIN, None, None, None)
}

/// `cargo build --release --bin <bin> [--no-default-features --features <features>]` in
/// `firmware_dir` (which has its own `.cargo/config.toml` selecting `thumbv7em-none-eabihf`),
/// with a clean environment (no inherited `CARGO_TARGET_DIR`, `RUSTFLAGS`, ... from a parent
/// cargo), `SSVR_SCENE` set to `scene` (absolute) or removed and `SSVR_MODEL` set to `model`
/// or removed (the firmware's default, rectangular). Returns the ELF.
pub fn cargo_build(
    firmware_dir: &Path,
    bin: &str,
    features: Option<&str>,
    scene: Option<&Path>,
    model: Option<Model>,
) -> Result<PathBuf> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(firmware_dir).args([
        "build",
        "--release",
        "--bin",
        bin,
        "--message-format=json-render-diagnostics",
    ]);
    if let Some(f) = features {
        cmd.args(["--no-default-features", "--features", f]);
    }
    cmd.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    for (key, _) in std::env::vars_os() {
        if let Some(k) = key.to_str() {
            if leaks_into_nested_cargo(k) {
                cmd.env_remove(k);
            }
        }
    }
    match scene {
        Some(p) => cmd.env("SSVR_SCENE", p),
        None => cmd.env_remove("SSVR_SCENE"),
    };
    match model {
        Some(m) => cmd.env("SSVR_MODEL", m.name()),
        None => cmd.env_remove("SSVR_MODEL"),
    };
    let out = cmd
        .output()
        .with_context(|| format!("cannot run cargo in {}", firmware_dir.display()))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        bail!(
            "firmware build of `{bin}` failed in {} ({}):\n{}",
            firmware_dir.display(),
            out.status,
            tail(&stderr, 60)
        );
    }
    let mut elf = None;
    for line in stdout.lines() {
        let Ok(msg) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        if msg["reason"] == "compiler-artifact" && msg["target"]["name"] == bin {
            if let Some(exe) = msg["executable"].as_str() {
                elf = Some(PathBuf::from(exe));
            }
        }
    }
    let elf = elf.ok_or_else(|| anyhow!("cargo built no `{bin}` executable"))?;
    if !elf.is_file() {
        bail!("the firmware image {} does not exist", elf.display());
    }
    Ok(elf)
}

/// The scene parameters the firmware compiles in, as a scene TOML in host-sim's layout (what
/// `firmware/build.rs` reads): structure, static friction, gravity, sample rate, displacement
/// noise and ranges.
/// Values are written with Rust's round-trip float formatting, so the image gets exactly the
/// scene's f64 values (and checks log headers against them bit for bit). Two scenes with the
/// same parameters give the same text, hence the same image without a rebuild.
pub fn firmware_scene_toml(scene: &Scene) -> String {
    let p = scene.structure.params();
    let s = &scene.sensors;
    format!(
        "# Written by host-sim (qemu_runner::firmware_scene_toml): the firmware parameters of a scene.\n\
         gravity_m_s2 = {g:?}\n\n[structure]\nm1_kg = {m1:?}\nm2_kg = {m2:?}\n\
         natural_frequency_hz = {f:?}\ndamping_ratio = {xi:?}\nfriction_coefficient = {mu:?}\n\
         static_friction_coefficient = {mu_s:?}\n\n\
         [sampling]\nrate_hz = {rate:?}\n\n[sensors]\naccel_range_m_s2 = {ar:?}\n\
         disp_range_m = {dr:?}\ndisp_noise_rms_m = {dn:?}\n",
        g = p.gravity_m_s2,
        m1 = p.m1_kg,
        m2 = p.m2_kg,
        f = p.natural_frequency_hz,
        xi = p.damping_ratio,
        mu = p.friction_coefficient,
        mu_s = scene.static_friction_coefficient,
        rate = scene.rate_hz,
        ar = s.accel_range_m_s2,
        dr = s.disp_range_m,
        dn = s.disp_noise_rms_m,
    )
}

/// Images built for a scene by [`build_for_scene`].
#[derive(Debug, Clone)]
pub struct SceneImages {
    /// The estimator model compiled in.
    pub model: Model,
    /// The QEMU image, copied out of `firmware/target`.
    pub qemu_elf: PathBuf,
    /// The board image's ELF copy, or why it could not be built for the scene (e.g. a
    /// non-integer sample rate).
    pub board_elf: std::result::Result<PathBuf, String>,
    /// The scene file the images were built with (`SSVR_SCENE`).
    pub scene_file: PathBuf,
    /// Wall time of the builds (s).
    pub build_s: f64,
}

/// Build the QEMU image (and, with `board`, the board image) for `scene` with the firmware's
/// default model (rectangular): [`build_for_scene_model`].
pub fn build_for_scene(
    firmware_dir: &Path,
    scene: &Scene,
    out_dir: &Path,
    board: bool,
) -> Result<SceneImages> {
    build_for_scene_model(firmware_dir, scene, Model::Rectangular, out_dir, board)
}

/// Build the QEMU image (and, with `board`, the board image) for `scene` and the estimator
/// `model` (`SSVR_MODEL`) and copy the ELFs to `out_dir` (`ssvr-qemu.elf`, `ssvr-board.elf`). The scene's firmware parameters
/// ([`firmware_scene_toml`]) go to `firmware/target/host-sim/scene.toml` (rewritten only when
/// they change, so cargo rebuilds only then) and `SSVR_SCENE` names that file. Concurrent calls
/// (parallel tests) are serialised by an exclusive lock on `firmware/target/host-sim/build.lock`,
/// held until the ELFs are copied.
pub fn build_for_scene_model(
    firmware_dir: &Path,
    scene: &Scene,
    model: Model,
    out_dir: &Path,
    board: bool,
) -> Result<SceneImages> {
    let start = Instant::now();
    let dir = firmware_dir.join("target").join("host-sim");
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let lock_path = dir.join("build.lock");
    let lock = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&lock_path)
        .with_context(|| format!("cannot open {}", lock_path.display()))?;
    lock.lock()
        .with_context(|| format!("cannot lock {}", lock_path.display()))?;
    let scene_file = dir.join("scene.toml");
    let text = firmware_scene_toml(scene);
    if std::fs::read_to_string(&scene_file).ok().as_deref() != Some(text.as_str()) {
        std::fs::write(&scene_file, &text)
            .with_context(|| format!("cannot write {}", scene_file.display()))?;
    }
    let scene_file = scene_file
        .canonicalize()
        .with_context(|| format!("no scene file at {}", scene_file.display()))?;
    let built = cargo_build(firmware_dir, QEMU_BIN, None, Some(&scene_file), Some(model))?;
    let qemu_elf = out_dir.join(format!("{QEMU_BIN}.elf"));
    std::fs::copy(&built, &qemu_elf)
        .with_context(|| format!("cannot copy {} to {}", built.display(), qemu_elf.display()))?;
    let board_elf = if board {
        match cargo_build(
            firmware_dir,
            BOARD_BIN,
            Some("board"),
            Some(&scene_file),
            Some(model),
        ) {
            Ok(built) => {
                let elf = out_dir.join(format!("{BOARD_BIN}.elf"));
                std::fs::copy(&built, &elf)
                    .with_context(|| format!("cannot copy {}", built.display()))?;
                Ok(elf)
            }
            Err(e) => Err(format!("{e:#}")),
        }
    } else {
        Err("not built".to_string())
    };
    drop(lock);
    Ok(SceneImages {
        model,
        qemu_elf,
        board_elf,
        scene_file,
        build_s: start.elapsed().as_secs_f64(),
    })
}

fn tail(s: &str, lines: usize) -> String {
    let v: Vec<&str> = s.lines().collect();
    v[v.len().saturating_sub(lines)..].join("\n")
}

/// What a QEMU run produced.
#[derive(Debug, Clone)]
pub struct QemuOutput {
    /// The raw defmt stream (semihosting writes to QEMU's stdout).
    pub stdout: Vec<u8>,
    /// QEMU's own messages.
    pub stderr: Vec<u8>,
    /// Exit status (the firmware's semihosting exit code), `None` if killed.
    pub status: Option<i32>,
    /// The run was killed at the timeout.
    pub timed_out: bool,
}

/// The QEMU program: `$QEMU_SYSTEM_ARM`, else `qemu-system-arm`.
pub fn qemu_program() -> std::ffi::OsString {
    std::env::var_os("QEMU_SYSTEM_ARM").unwrap_or_else(|| "qemu-system-arm".into())
}

/// Whether [`qemu_program`] runs (`--version`).
pub fn qemu_available() -> bool {
    Command::new(qemu_program())
        .arg("--version")
        .stdin(Stdio::null())
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

/// An error unless QEMU is installed; the message says how to install it.
pub fn require_qemu() -> Result<()> {
    if qemu_available() {
        Ok(())
    } else {
        bail!(
            "{} not found: run `apt-get install -y qemu-system-arm` (or set QEMU_SYSTEM_ARM)",
            qemu_program().to_string_lossy()
        )
    }
}

/// The QEMU command line for `elf` (the log is `log_name` relative to the working directory).
pub fn qemu_command(elf: &Path, log_name: &str) -> Command {
    let mut cmd = Command::new(qemu_program());
    cmd.args([
        "-machine",
        "mps2-an386",
        "-cpu",
        "cortex-m4",
        "-nographic",
        "-monitor",
        "none",
        "-semihosting-config",
        "enable=on,target=native",
        "-icount",
        "shift=0",
        "-kernel",
    ])
    .arg(elf)
    .args(["-append", log_name]);
    cmd
}

/// Run `elf` under QEMU with the sensor log `log_path` and return everything it produced, exit
/// status included. QEMU runs in the log's directory and gets the log's file name as its
/// semihosting command line (`-append`), which the firmware opens. Killed after `timeout`.
pub fn run_qemu_output(elf: &Path, log_path: &Path, timeout: Duration) -> Result<QemuOutput> {
    let elf = elf
        .canonicalize()
        .with_context(|| format!("no firmware image at {}", elf.display()))?;
    let log = log_path
        .canonicalize()
        .with_context(|| format!("no sensor log at {}", log_path.display()))?;
    let dir = log
        .parent()
        .ok_or_else(|| anyhow!("the log {} has no directory", log.display()))?;
    let name = log
        .file_name()
        .and_then(|n| n.to_str())
        .filter(|n| !n.contains(char::is_whitespace) && n.len() < 200)
        .ok_or_else(|| {
            anyhow!(
                "the log file name {} must be UTF-8, without spaces, < 200 bytes",
                log.display()
            )
        })?;
    let mut child = qemu_command(&elf, name)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .with_context(|| {
            format!(
                "cannot start {} (not installed? run `apt-get install -y qemu-system-arm`)",
                qemu_program().to_string_lossy()
            )
        })?;
    let mut out = child
        .stdout
        .take()
        .ok_or_else(|| anyhow!("no stdout pipe"))?;
    let mut err = child
        .stderr
        .take()
        .ok_or_else(|| anyhow!("no stderr pipe"))?;
    let out_reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = out.read_to_end(&mut v);
        v
    });
    let err_reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = err.read_to_end(&mut v);
        v
    });
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        if let Some(s) = child.try_wait().context("waiting for QEMU")? {
            break s;
        }
        if start.elapsed() > timeout {
            timed_out = true;
            let _ = child.kill();
            break child.wait().context("waiting for the killed QEMU")?;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let stdout = out_reader
        .join()
        .map_err(|_| anyhow!("stdout reader panicked"))?;
    let stderr = err_reader
        .join()
        .map_err(|_| anyhow!("stderr reader panicked"))?;
    Ok(QemuOutput {
        stdout,
        stderr,
        status: status.code(),
        timed_out,
    })
}

/// Run `elf` on the sensor log `log_path` (see [`run_qemu_output`]) and return the raw defmt
/// bytes. A timeout or a non-zero exit status is an error that quotes the decoded messages.
pub fn run_qemu(elf: &Path, log_path: &Path, timeout: Duration) -> Result<Vec<u8>> {
    let out = run_qemu_output(elf, log_path, timeout)?;
    if out.timed_out || out.status != Some(0) {
        let messages = match decode_frames(elf, &out.stdout) {
            Ok(frames) => frames
                .iter()
                .rev()
                .take(20)
                .rev()
                .map(|f| f.to_string())
                .collect::<Vec<_>>()
                .join("\n"),
            Err(e) => format!("(undecodable output: {e})"),
        };
        bail!(
            "QEMU {} (status {:?}); last firmware messages:\n{}\nQEMU stderr:\n{}",
            if out.timed_out { "timed out" } else { "failed" },
            out.status,
            messages,
            tail(&String::from_utf8_lossy(&out.stderr), 20)
        );
    }
    Ok(out.stdout)
}

/// One decoded defmt message.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedFrame {
    /// Log level (`"info"`, `"error"`, ...), `None` for `println!`-style frames.
    pub level: Option<String>,
    /// The formatted message.
    pub message: String,
}

impl std::fmt::Display for DecodedFrame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.level {
            Some(l) => write!(f, "{l:>5} {}", self.message),
            None => write!(f, "{}", self.message),
        }
    }
}

/// The friction event of a frame (`ev=.. level=.. age=..`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameEvent {
    /// One of [`event_kind`].
    pub kind: u8,
    /// Friction level after the event (units of μ(m1+m2)g): −1, 0, +1.
    pub level: i8,
    /// Samples between the event and this frame's sample.
    pub age_samples: f32,
}

impl FrameEvent {
    /// Whether the firmware's rectangular model pushes this event to the estimator (all but a
    /// stick; the stick-slip model pushes every event, the fixed-base model none).
    pub fn pushes(&self) -> bool {
        self.kind != event_kind::STICK
    }
}

/// A per-sample frame of the firmware (`sample idx=.. flags=.. table=.. ... pred=..`, then
/// `ev=.. level=.. age=..` when the sample has a friction event).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleFrame {
    /// Sample index.
    pub index: u32,
    /// Bits of [`frame_flags`].
    pub flags: u8,
    /// Table acceleration (m/s²).
    pub table_accel_m_s2: f32,
    /// Base acceleration (m/s²).
    pub base_accel_m_s2: f32,
    /// Top-mass acceleration, measured (m/s²).
    pub top_accel_m_s2: f32,
    /// Base-to-table displacement (m).
    pub displacement_m: f32,
    /// Top-mass acceleration predicted by the estimator (m/s²).
    pub prediction_m_s2: f32,
    /// The friction event of this sample.
    pub event: Option<FrameEvent>,
}

impl DecodedFrame {
    /// The first word of the message (`sample`, `icount`, `stats`, `log`, `done`, ...).
    pub fn kind(&self) -> &str {
        self.message.split_whitespace().next().unwrap_or("")
    }

    /// The value of a `key=value` field of the message.
    pub fn field(&self, key: &str) -> Option<&str> {
        self.message
            .split_whitespace()
            .find_map(|w| w.split_once('=').filter(|(k, _)| *k == key).map(|(_, v)| v))
    }

    fn parse<T: std::str::FromStr>(&self, key: &str) -> Option<T> {
        self.field(key).and_then(|v| v.parse().ok())
    }

    /// The frame as a [`SampleFrame`], if it is one.
    pub fn sample(&self) -> Option<SampleFrame> {
        if self.kind() != "sample" {
            return None;
        }
        Some(SampleFrame {
            index: self.parse("idx")?,
            flags: self.parse("flags")?,
            table_accel_m_s2: self.parse("table")?,
            base_accel_m_s2: self.parse("base")?,
            top_accel_m_s2: self.parse("top")?,
            displacement_m: self.parse("disp")?,
            prediction_m_s2: self.parse("pred")?,
            event: match self.field("ev") {
                None => None,
                Some(_) => Some(FrameEvent {
                    kind: self.parse("ev")?,
                    level: self.parse("level")?,
                    age_samples: self.parse("age")?,
                }),
            },
        })
    }
}

/// Decode a defmt byte stream with the interning table of `elf`.
pub fn decode_frames(elf: &Path, bytes: &[u8]) -> Result<Vec<DecodedFrame>> {
    let image =
        std::fs::read(elf).with_context(|| format!("cannot read the ELF {}", elf.display()))?;
    let table = defmt_decoder::Table::parse(&image)
        .with_context(|| format!("cannot read the defmt table of {}", elf.display()))?
        .ok_or_else(|| anyhow!("{} has no defmt data", elf.display()))?;
    let mut decoder = table.new_stream_decoder();
    let mut frames = Vec::new();
    // Fed in chunks: the stream decoder drains its buffer from the front, which is quadratic in
    // the buffered length (a 320 000-frame stream took a minute in one piece).
    for chunk in bytes.chunks(4096) {
        decoder.received(chunk);
        loop {
            match decoder.decode() {
                Ok(f) => frames.push(DecodedFrame {
                    level: f.level().map(|l| l.as_str().to_string()),
                    message: f.display_message().to_string(),
                }),
                Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
                Err(defmt_decoder::DecodeError::Malformed) => {
                    if !table.encoding().can_recover() {
                        bail!(
                            "malformed defmt frame after {} frames (raw encoding)",
                            frames.len()
                        );
                    }
                }
            }
        }
    }
    Ok(frames)
}

/// The per-sample frames, in order.
pub fn sample_frames(frames: &[DecodedFrame]) -> Vec<SampleFrame> {
    frames.iter().filter_map(DecodedFrame::sample).collect()
}

/// Instruction counts the QEMU image measures after the replay (see `firmware/README.md`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InstructionCounts {
    /// Instructions of the calibration loop.
    pub calibration_instructions: u32,
    /// SysTick ticks they took.
    pub calibration_ticks: u32,
    /// Executed instructions per SysTick tick (40 on mps2-an386 with `-icount shift=0`).
    pub instructions_per_tick: f64,
    /// Instructions of one steady-state update of the model's estimator, loop overhead removed
    /// (rectangular: `update()` while sliding; stick-slip: `update(table, top)` while sliding, μ
    /// identified; fixed-base: `update(table, top)` stuck).
    pub instructions_per_sample: f64,
    /// Extra instructions of a sample with a reversal (`push_reversal(±1, 0.5)` or
    /// `push_event(±1, 0.5)` + its effect on the update), over a steady-state sample; `None`
    /// for the fixed-base model (it pushes no event).
    pub instructions_per_reversal: Option<f64>,
    /// Stick-slip and fixed-base models: instructions of a steady-state stuck update.
    pub instructions_per_sample_stuck: Option<f64>,
    /// Stick-slip model: extra instructions of a sample with an event [`Self::max_event_age`]
    /// samples old (the whole history re-simulated), over a steady-state sample.
    pub instructions_per_event_max_age: Option<f64>,
    /// The age of those events (samples).
    pub max_event_age: Option<f64>,
    /// Stick-slip model: instructions of a steady-state sliding update without the μ
    /// identification (the prediction alone).
    pub instructions_per_sample_without_identification: Option<f64>,
    /// Stick-slip and fixed-base models: the estimator's block size in the pipeline
    /// (`update_block`, `icount block`).
    pub block_size: Option<u32>,
    /// Stick-slip model: instructions per sliding sample (μ identified) in blocks of
    /// [`Self::block_size`].
    pub instructions_per_sample_in_blocks: Option<f64>,
    /// Stick-slip and fixed-base models: instructions per stuck sample in blocks.
    pub instructions_per_sample_stuck_in_blocks: Option<f64>,
    /// Updates timed in the steady-state block.
    pub updates: u32,
    /// SysTick ticks of the steady-state block.
    pub update_ticks: u32,
    /// SysTick ticks of the same loop without the update.
    pub loop_ticks: u32,
    /// Samples with a reversal timed.
    pub reversals: u32,
    /// SysTick ticks of the reversal block.
    pub reversal_ticks: u32,
    /// Reversals the estimator rejected during the benchmark.
    pub reversal_errors: u32,
    /// Instructions of the reversal detector per sample in its steady state (sliding, a new
    /// extremum every sample), generator loop removed.
    pub detector_instructions_per_sample: Option<f64>,
    /// Extra instructions of a sample where the detector reports a reversal (vertex fits).
    pub detector_instructions_per_reversal: Option<f64>,
    /// Instructions per sample of the firmware's whole step in batches of 16 (flags, detector,
    /// estimator, frames; no I/O) in the steady sliding state.
    pub pipeline_instructions_per_sample: Option<f64>,
    /// Extra instructions of the detector for a stick and the slip start that ends it (their kink
    /// fits), over sliding samples.
    pub detector_instructions_per_stick: Option<f64>,
}

/// Extract the instruction counts from the `icount` messages. Computed on the host from the raw
/// ticks in f64 (the firmware's own f32 summary is a cross-check).
pub fn instruction_counts(frames: &[DecodedFrame]) -> Option<InstructionCounts> {
    let cal = frames
        .iter()
        .find(|f| f.kind() == "icount" && f.message.starts_with("icount calibration"))?;
    let raw = frames
        .iter()
        .find(|f| f.kind() == "icount" && f.message.starts_with("icount raw"))?;
    let calibration_instructions: u32 = cal.parse("instructions")?;
    let calibration_ticks: u32 = cal.parse("ticks")?;
    if calibration_ticks == 0 {
        return None;
    }
    let ipt = f64::from(calibration_instructions) / f64::from(calibration_ticks);
    let updates: u32 = raw.parse("updates")?;
    let update_ticks: u32 = raw.parse("update_ticks")?;
    let loop_ticks: u32 = raw.parse("loop_ticks")?;
    let reversals: u32 = raw.parse("reversals")?;
    let reversal_ticks: u32 = raw.parse("reversal_ticks")?;
    let reversal_errors: u32 = raw.parse("reversal_errors")?;
    if updates == 0 {
        return None;
    }
    let overhead = f64::from(loop_ticks) * ipt / f64::from(updates);
    let per_sample = f64::from(update_ticks) * ipt / f64::from(updates) - overhead;
    let per_reversal = (reversals > 0)
        .then(|| f64::from(reversal_ticks) * ipt / f64::from(reversals) - overhead - per_sample);
    let ss = frames
        .iter()
        .find(|f| f.message.starts_with("icount stick_slip "));
    let stuck = ss.and_then(|m| {
        let n: u32 = m.parse("stuck_updates")?;
        let ticks: u32 = m.parse("stuck_ticks")?;
        (n > 0).then(|| f64::from(ticks) * ipt / f64::from(n) - overhead)
    });
    let predict = ss.and_then(|m| {
        let n: u32 = m.parse("predict_updates")?;
        let ticks: u32 = m.parse("predict_ticks")?;
        (n > 0).then(|| f64::from(ticks) * ipt / f64::from(n) - overhead)
    });
    let long = ss.and_then(|m| {
        let n: u32 = m.parse("long_events")?;
        let ticks: u32 = m.parse("long_event_ticks")?;
        let age: f64 = m.parse("max_age")?;
        (n > 0).then(|| {
            (
                f64::from(ticks) * ipt / f64::from(n) - overhead - per_sample,
                age,
            )
        })
    });
    let blk = frames
        .iter()
        .find(|f| f.message.starts_with("icount block "));
    let block_size = blk.and_then(|m| m.parse::<u32>("batch"));
    let in_blocks = |field: &str| {
        blk.and_then(|m| {
            let n: u32 = m.parse("updates")?;
            let lp: u32 = m.parse("loop_ticks")?;
            let ticks: u32 = m.parse(field)?;
            // A block the estimator refused (never expected) voids the figures.
            let errors: u32 = m.parse("errors")?;
            (n > 0 && ticks > 0 && errors == 0)
                .then(|| (f64::from(ticks) - f64::from(lp)) * ipt / f64::from(n))
        })
    };
    let det = frames
        .iter()
        .find(|f| f.message.starts_with("icount detector "));
    let pipe = frames
        .iter()
        .find(|f| f.message.starts_with("icount pipeline "));
    let per = |ticks: u32, n: u32| f64::from(ticks) * ipt / f64::from(n);
    let detector = det.and_then(|d| {
        let n: u32 = d.parse("samples")?;
        let lp: u32 = d.parse("loop_ticks")?;
        let ramp: u32 = d.parse("ramp_ticks")?;
        let tri: u32 = d.parse("triangle_ticks")?;
        let revs: u32 = d.parse("reversals")?;
        if n == 0 || revs == 0 {
            return None;
        }
        Some((
            per(ramp, n) - per(lp, n),
            (f64::from(tri) - f64::from(ramp)) * ipt / f64::from(revs),
        ))
    });
    let stick = frames
        .iter()
        .find(|f| f.message.starts_with("icount detector_stick "))
        .and_then(|m| {
            let ramp: u32 = m.parse("ramp_ticks")?;
            let stair: u32 = m.parse("stair_ticks")?;
            let sticks: u32 = m.parse("sticks")?;
            (sticks > 0).then(|| (f64::from(stair) - f64::from(ramp)) * ipt / f64::from(sticks))
        });
    let pipeline = pipe.and_then(|p| {
        let n: u32 = p.parse("samples")?;
        let lp: u32 = p.parse("loop_ticks")?;
        let step: u32 = p.parse("step_ticks")?;
        (n > 0).then(|| per(step, n) - per(lp, n))
    });
    Some(InstructionCounts {
        calibration_instructions,
        calibration_ticks,
        instructions_per_tick: ipt,
        instructions_per_sample: per_sample,
        instructions_per_reversal: per_reversal,
        instructions_per_sample_stuck: stuck,
        instructions_per_event_max_age: long.map(|l| l.0),
        max_event_age: long.map(|l| l.1),
        instructions_per_sample_without_identification: predict,
        block_size,
        instructions_per_sample_in_blocks: in_blocks("slide_ticks"),
        instructions_per_sample_stuck_in_blocks: in_blocks("stuck_ticks"),
        updates,
        update_ticks,
        loop_ticks,
        reversals,
        reversal_ticks,
        reversal_errors,
        detector_instructions_per_sample: detector.map(|d| d.0),
        detector_instructions_per_reversal: detector.map(|d| d.1),
        pipeline_instructions_per_sample: pipeline,
        detector_instructions_per_stick: stick,
    })
}

/// Flash and RAM use of a firmware ELF, in bytes: flash = allocated sections with contents
/// (vector table, `.text`, `.rodata`, and the load image of `.data`); RAM = writable allocated
/// sections (`.data`, `.bss`, `.uninit`). The stack (the rest of RAM) is not counted.
pub fn elf_sizes(elf: &Path) -> Result<(u64, u64)> {
    use object::read::elf::{ElfFile32, FileHeader, SectionHeader};
    let data = std::fs::read(elf).with_context(|| format!("cannot read {}", elf.display()))?;
    let file = ElfFile32::<object::LittleEndian>::parse(&*data)
        .with_context(|| format!("{} is not a 32-bit little-endian ELF", elf.display()))?;
    let endian = file.endian();
    let (mut flash, mut ram) = (0u64, 0u64);
    for section in file.elf_header().sections(endian, &*data)?.iter() {
        let flags = u64::from(section.sh_flags(endian));
        if flags & u64::from(object::elf::SHF_ALLOC) == 0 {
            continue;
        }
        let size = u64::from(section.sh_size(endian));
        let nobits = section.sh_type(endian) == object::elf::SHT_NOBITS;
        if !nobits {
            flash += size;
        }
        if flags & u64::from(object::elf::SHF_WRITE) != 0 {
            ram += size;
        }
    }
    Ok((flash, ram))
}
