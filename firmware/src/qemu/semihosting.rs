//! Semihosting on the QEMU image: exit with a status, the command line, and a buffered
//! read-only host file (the sensor log).

use cortex_m_semihosting::nr;
use ssvr_proto::log::LogError;

/// Default log file name (relative to QEMU's working directory).
pub const DEFAULT_LOG: &str = match option_env!("SSVR_QEMU_LOG") {
    Some(p) => p,
    None => "sensor.ssvrlog",
};

/// Exit QEMU with `code` (SYS_EXIT_EXTENDED, ADP_Stopped_ApplicationExit + subcode: QEMU exits
/// with that status).
pub fn exit(code: u32) -> ! {
    let block = [0x2_0026usize, code as usize];
    loop {
        // SAFETY: SYS_EXIT_EXTENDED (0x20) takes a pointer to a two-word parameter block.
        unsafe {
            cortex_m_semihosting::syscall(0x20, &block);
        }
    }
}

/// A host file opened through semihosting.
pub struct HostFile {
    handle: usize,
}

impl HostFile {
    /// Open `path` (bytes without NUL, at most 255) read-only binary.
    pub fn open(path: &[u8]) -> Result<Self, LogError> {
        let mut z = [0u8; 256];
        if path.len() >= z.len() {
            return Err(LogError::Open);
        }
        z[..path.len()].copy_from_slice(path);
        // SAFETY: OPEN takes (NUL-terminated name, mode, length without the NUL).
        let h = unsafe {
            cortex_m_semihosting::syscall(
                nr::OPEN,
                &[z.as_ptr() as usize, nr::open::R_BINARY, path.len()],
            )
        };
        if h == usize::MAX {
            Err(LogError::Open)
        } else {
            Ok(Self { handle: h })
        }
    }

    /// Read up to `buf.len()` bytes; returns how many were read (0 at end of file).
    pub fn read(&mut self, buf: &mut [u8]) -> Result<usize, LogError> {
        // SAFETY: READ takes (handle, buffer, length) and returns the bytes NOT read.
        let not_read = unsafe {
            cortex_m_semihosting::syscall(
                nr::READ,
                &[self.handle, buf.as_mut_ptr() as usize, buf.len()],
            )
        };
        if not_read > buf.len() {
            return Err(LogError::Io);
        }
        Ok(buf.len() - not_read)
    }
}

impl Drop for HostFile {
    fn drop(&mut self) {
        // SAFETY: CLOSE takes the handle.
        unsafe {
            cortex_m_semihosting::syscall(nr::CLOSE, &[self.handle]);
        }
    }
}

/// Buffered reader over a [`HostFile`].
pub struct Reader {
    file: HostFile,
    buf: [u8; 512],
    pos: usize,
    len: usize,
}

impl Reader {
    pub fn new(file: HostFile) -> Self {
        Self {
            file,
            buf: [0; 512],
            pos: 0,
            len: 0,
        }
    }

    /// Fill `out` entirely: `Ok(true)`; end of file before the first byte: `Ok(false)`;
    /// end of file inside: `Err(Truncated)`.
    pub fn read_exact(&mut self, out: &mut [u8]) -> Result<bool, LogError> {
        let mut done = 0;
        while done < out.len() {
            if self.pos == self.len {
                self.pos = 0;
                self.len = self.file.read(&mut self.buf)?;
                if self.len == 0 {
                    return if done == 0 {
                        Ok(false)
                    } else {
                        Err(LogError::Truncated)
                    };
                }
            }
            let n = (out.len() - done).min(self.len - self.pos);
            out[done..done + n].copy_from_slice(&self.buf[self.pos..self.pos + n]);
            self.pos += n;
            done += n;
        }
        Ok(true)
    }
}

/// The log path: the last word after the program name on the semihosting command line.
pub fn log_path(buf: &mut [u8; 256]) -> &[u8] {
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: GET_CMDLINE takes a pointer to (buffer, length) and writes the NUL-terminated
    // command line and its length.
    let r = unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    // SAFETY: the host wrote the length through the pointer above.
    let len = unsafe { core::ptr::read_volatile(&block[1]) };
    if r != 0 || len > buf.len() {
        return DEFAULT_LOG.as_bytes();
    }
    // "<kernel path> <append>": the log name is the last word when there are at least two
    // (the host runner passes a name without spaces; the kernel path may contain some).
    let line = &buf[..len];
    let mut words = line
        .split(|&c| c == b' ' || c == 0)
        .filter(|w| !w.is_empty());
    let _program = words.next();
    words.next_back().unwrap_or(DEFAULT_LOG.as_bytes())
}
