//! The firmware's images and QEMU: build an image for a scene and a model, run it on a sensor
//! log, and size it.
//!
//! * [`firmware_scene_toml`], [`build_for_scene`], [`build_for_scene_model`]: build an image for
//!   a [`Scene`] and an estimator model (`cargo build --release` in `firmware/` with
//!   `SSVR_SCENE` naming a file with the scene's firmware parameters and `SSVR_MODEL` the model,
//!   the parent cargo's target/flags environment removed, serialised by a file lock) and copy the
//!   ELF out; [`build_qemu_image`]: the same for the image's default scene and model;
//! * [`run_qemu`]: run the ELF under `qemu-system-arm -icount shift=0` with the log, return the
//!   raw defmt bytes (decoded by [`super::decode`]);
//! * [`elf_sizes`]: flash and RAM use of an image.
//!
//! Plain functions, no global state; errors are [`anyhow::Error`]s with context.

use crate::model::Model;
use crate::scene::Scene;
use anyhow::{anyhow, bail, Context, Result};
use ssvr_proto::Mode;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The name of the firmware's board binary.
pub const BOARD_BIN: &str = "ssvr-board";

/// The name of the firmware's QEMU binary.
pub const QEMU_BIN: &str = "ssvr-qemu";

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
        "SSVR_MODE",
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
    cargo_build(firmware_dir, QEMU_BIN, None, None, None, None, None)
}

/// `cargo build --release --bin <bin> [--no-default-features --features <features>]` in
/// `firmware_dir` (which has its own `.cargo/config.toml` selecting `thumbv7em-none-eabihf`),
/// with a clean environment (no inherited `CARGO_TARGET_DIR`, `RUSTFLAGS`, ... from a parent
/// cargo), `SSVR_SCENE` set to `scene` (absolute) or removed, `SSVR_MODEL` set to `model`
/// or removed (the firmware's default, rectangular), `SSVR_MODE` set to `mode` or removed
/// (fuse), and `SSVR_PLANNED_START` set to `planned` (the plan's
/// [`planned_start`](ssvr_proto::Plan::planned_start): its two f32s' bits in hex,
/// `accel,rise`, or `none`) or removed (the firmware then plans the scene file's own input, if
/// it has one). Returns the ELF.
pub fn cargo_build(
    firmware_dir: &Path,
    bin: &str,
    features: Option<&str>,
    scene: Option<&Path>,
    model: Option<Model>,
    mode: Option<Mode>,
    planned: Option<Option<ssvr_proto::PlannedStart>>,
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
    match mode {
        Some(m) => cmd.env("SSVR_MODE", m.name()),
        None => cmd.env_remove("SSVR_MODE"),
    };
    match planned {
        Some(Some(p)) => cmd.env("SSVR_PLANNED_START", p.to_string()),
        Some(None) => cmd.env("SSVR_PLANNED_START", "none"),
        None => cmd.env_remove("SSVR_PLANNED_START"),
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
/// `firmware/build.rs` reads): the estimator's prior of the structure and static friction (as
/// `[structure]`), gravity, sample rate, sensor noise and ranges, and the rest before the input.
/// Values are written with Rust's round-trip float formatting, so the image gets exactly the
/// scene's f64 values (and checks log headers against them bit for bit). Two scenes with the
/// same parameters give the same text, hence the same image without a rebuild.
pub fn firmware_scene_toml(scene: &Scene) -> String {
    // The firmware compiles in what the controller is told: the prior (`[estimator]`), written
    // as its `[structure]`.
    let p = &scene.estimator.params;
    let s = &scene.sensors;
    // The rest before the input (`[input] start_s`): the firmware reads only `start_s` of the
    // input (its motion is the log's), so a placeholder motion carries it.
    let rest = if scene.start_s > 0.0 {
        format!(
            "\n[input]\nkind = \"harmonic\"\namplitude_m_s2 = 0.0\nperiod_s = 1.0\nstart_s = {:?}\n",
            scene.start_s
        )
    } else {
        String::new()
    };
    let text = format!(
        "# Written by host-sim (qemu::image::firmware_scene_toml): the firmware parameters of a scene.\n\
         gravity_m_s2 = {g:?}\n\n[structure]\nm1_kg = {m1:?}\nm2_kg = {m2:?}\n\
         natural_frequency_hz = {f:?}\ndamping_ratio = {xi:?}\nfriction_coefficient = {mu:?}\n\
         static_friction_coefficient = {mu_s:?}\n\n\
         [sampling]\nrate_hz = {rate:?}\n\n[sensors]\naccel_range_m_s2 = {ar:?}\n\
         disp_range_m = {dr:?}\ndisp_noise_rms_m = {dn:?}\naccel_noise_rms_m_s2 = {an:?}\n",
        g = p.gravity_m_s2,
        m1 = p.m1_kg,
        m2 = p.m2_kg,
        f = p.natural_frequency_hz,
        xi = p.damping_ratio,
        mu = p.friction_coefficient,
        mu_s = scene.estimator.static_friction_coefficient,
        rate = scene.rate_hz,
        ar = s.accel_range_m_s2,
        dr = s.disp_range_m,
        dn = s.disp_noise_rms_m,
        an = s.accel_noise_rms_m_s2,
    );
    // The prior's friction law (a velocity-dependent one makes the model follow it).
    let friction = match scene.estimator.friction {
        ssvr_core::FrictionLaw::Coulomb => String::new(),
        ssvr_core::FrictionLaw::VelocityDependent { mu_slow, rate_s_m } => format!(
            "\n[friction]\nlaw = \"velocity-dependent\"\nmu_slow = {mu_slow:?}\nrate_s_m = {rate_s_m:?}\n"
        ),
    };
    text + &friction + &rest
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
    build_for_scene_mode(firmware_dir, scene, model, Mode::Fuse, out_dir, board)
}

/// [`build_for_scene_model`] in `mode` (`SSVR_MODE`).
pub fn build_for_scene_mode(
    firmware_dir: &Path,
    scene: &Scene,
    model: Model,
    mode: Mode,
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
    // (The firmware's scene file has no input: the planned start, the host plan's, goes by
    // itself.)
    let planned = Some(crate::pipeline::plan_for_mode(scene, model, mode)?.planned_start);
    let built = cargo_build(
        firmware_dir,
        QEMU_BIN,
        None,
        Some(&scene_file),
        Some(model),
        Some(mode),
        planned,
    )?;
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
            Some(mode),
            planned,
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

/// Keep a copy of the QEMU image `elf` that outlives the run, so its defmt table can decode a
/// saved stream later (`host-sim monitor --elf`): `firmware/target/host-sim/images/
/// ssvr-qemu-<FNV-1a 64 of the ELF>.elf` (absolute), named by its content so that parallel runs
/// of the same image share one file and a rebuilt image never overwrites an older one; written
/// to a temporary name and renamed into place. `cargo clean` in `firmware/` removes them.
pub fn keep_image(firmware_dir: &Path, elf: &Path) -> Result<PathBuf> {
    let bytes =
        std::fs::read(elf).with_context(|| format!("cannot read the ELF {}", elf.display()))?;
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    });
    let dir = firmware_dir.join("target").join("host-sim").join("images");
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let kept = dir.join(format!("{QEMU_BIN}-{hash:016x}.elf"));
    if std::fs::read(&kept).ok().as_deref() != Some(bytes.as_slice()) {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0);
        let tmp = dir.join(format!(".{QEMU_BIN}-{}-{nanos}.tmp", std::process::id()));
        std::fs::write(&tmp, &bytes).with_context(|| format!("cannot write {}", tmp.display()))?;
        std::fs::rename(&tmp, &kept)
            .with_context(|| format!("cannot rename {} to {}", tmp.display(), kept.display()))?;
    }
    kept.canonicalize()
        .with_context(|| format!("no image at {}", kept.display()))
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
///
/// No `-nographic`: its stdio serial port makes QEMU's stdout non-blocking, a semihosting write
/// that meets a full pipe then fails, and defmt-semihosting drops what it could not write (a
/// loaded CI machine once lost 2 110 of 320 000 frames). With `-display none -serial null`
/// stdout stays blocking and the firmware waits for its reader.
pub fn qemu_command(elf: &Path, log_name: &str) -> Command {
    let mut cmd = Command::new(qemu_program());
    cmd.args([
        "-machine",
        "mps2-an386",
        "-cpu",
        "cortex-m4",
        "-display",
        "none",
        "-serial",
        "null",
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
        let messages = match super::decode::decode(elf, &out.stdout) {
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
