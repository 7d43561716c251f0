//! Reads and writes at an offset in a file, on every platform the codec builds for.
//!
//! The codec reads a leaf's region of the raw index file, a leaf's keys from the scratch file
//! and a node's bytes from a `.tsc` file by offset, and fills the raw index file's regions by
//! offset. Unix offers this as `pread`/`pwrite` (`FileExt::read_exact_at`/`write_all_at`), which
//! leave the file cursor alone; Windows offers `seek_read`/`seek_write`, which may return short
//! and **move the file cursor** to the end of what they transferred. So no caller of these
//! functions may rely on the cursor: every codec file is either read and written only by offset,
//! or written sequentially first and only read by offset afterwards.

use std::fs::File;
use std::io;

/// Fills `buf` with the bytes of `file` at `offset`.
///
/// On Unix the file cursor is left where it was; on Windows it moves (see the module's note).
///
/// # Errors
///
/// The OS's error, or [`io::ErrorKind::UnexpectedEof`] when the file ends before `buf` is full.
pub fn read_exact_at(file: &File, buf: &mut [u8], offset: u64) -> io::Result<()> {
    #[cfg(unix)]
    {
        std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
    }
    #[cfg(windows)]
    {
        use std::os::windows::fs::FileExt;
        let (mut buf, mut offset) = (buf, offset);
        while !buf.is_empty() {
            match file.seek_read(buf, offset) {
                Ok(0) => {
                    return Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "failed to fill whole buffer",
                    ));
                }
                Ok(n) => {
                    buf = &mut buf[n..];
                    offset += n as u64;
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }
}

/// Writes all of `buf` to `file` at `offset`.
///
/// On Unix the file cursor is left where it was; on Windows it moves (see the module's note).
///
/// # Errors
///
/// The OS's error, or [`io::ErrorKind::WriteZero`] when the OS accepts no more bytes.
pub fn write_all_at(file: &File, buf: &[u8], offset: u64) -> io::Result<()> {
    #[cfg(unix)]
    {
        std::os::unix::fs::FileExt::write_all_at(file, buf, offset)
    }
    #[cfg(windows)]
    {
        use std::os::windows::fs::FileExt;
        let (mut buf, mut offset) = (buf, offset);
        while !buf.is_empty() {
            match file.seek_write(buf, offset) {
                Ok(0) => {
                    return Err(io::Error::new(
                        io::ErrorKind::WriteZero,
                        "failed to write whole buffer",
                    ));
                }
                Ok(n) => {
                    buf = &buf[n..];
                    offset += n as u64;
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_reads_back_by_offset_out_of_order() {
        let file = tempfile::tempfile().unwrap();
        write_all_at(&file, b"world", 6).unwrap();
        write_all_at(&file, b"hello ", 0).unwrap();
        let mut buf = [0u8; 5];
        read_exact_at(&file, &mut buf, 6).unwrap();
        assert_eq!(&buf, b"world");
        read_exact_at(&file, &mut buf, 0).unwrap();
        assert_eq!(&buf, b"hello");
    }

    #[test]
    fn reading_past_the_end_is_unexpected_eof() {
        let file = tempfile::tempfile().unwrap();
        write_all_at(&file, b"abc", 0).unwrap();
        let mut buf = [0u8; 4];
        let e = read_exact_at(&file, &mut buf, 0).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::UnexpectedEof);
    }
}
