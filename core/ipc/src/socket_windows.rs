//! The daemon's named pipe on Windows: created with a security descriptor that admits only the
//! current user, refused when another process already holds the name, and checked by clients
//! before they send anything (docs/protocol.md, "Transport").
//!
//! Windows' default DACL for a named pipe grants read access to Everyone and to Anonymous, so a
//! pipe created without a descriptor would let every account on the machine read requests and
//! replies. The descriptor here is `O:<user>D:P(A;;FA;;;<user>)`: owned by the user, one ACE
//! granting that user full access, protected from inheritance; nobody else (no Everyone, no
//! Anonymous, no other SID) can open the pipe or create an instance of it.

use super::{BindError, PIPE_PREFIX, is_pipe_name};
use interprocess::local_socket::{GenericFilePath, Listener, ListenerOptions, Stream, ToFsName};
use interprocess::os::windows::local_socket::ListenerOptionsExt;
use interprocess::os::windows::security_descriptor::SecurityDescriptor;
use std::io;
use std::os::windows::io::{AsHandle, AsRawHandle};
use std::path::Path;
use std::time::Duration;
use windows_sys::Win32::Foundation::{
    CloseHandle, ERROR_ACCESS_DENIED, ERROR_INSUFFICIENT_BUFFER, ERROR_PIPE_BUSY, GetLastError,
    HANDLE, HLOCAL, LocalFree,
};
use windows_sys::Win32::Security::Authorization::{
    ConvertSidToStringSidW, GetSecurityInfo, SE_KERNEL_OBJECT,
};
use windows_sys::Win32::Security::{
    ACL, DACL_SECURITY_INFORMATION, EqualSid, GetTokenInformation, OWNER_SECURITY_INFORMATION,
    PSECURITY_DESCRIPTOR, PSID, TOKEN_QUERY, TOKEN_USER, TokenUser,
};
use windows_sys::Win32::System::Threading::{GetCurrentProcess, OpenProcessToken};

/// Creates the pipe `path` (a `\\.\pipe\NAME`) as its first instance, owner-only.
pub(super) fn bind(path: &Path) -> Result<Listener, BindError> {
    let io_err = |source| BindError::Io {
        path: path.to_path_buf(),
        source,
    };
    if !path.to_str().is_some_and(is_pipe_name) {
        return Err(BindError::Unsafe {
            path: path.to_path_buf(),
            reason: format!(
                "on Windows the daemon listens on a named pipe {PIPE_PREFIX}NAME, not on a file"
            ),
        });
    }
    let sid = UserSid::current().map_err(io_err)?;
    let sddl = format!("O:{0}D:P(A;;FA;;;{0})", sid.to_string().map_err(io_err)?);
    let sddl = widestring::U16CString::from_str(&sddl)
        .map_err(|e| io_err(io::Error::new(io::ErrorKind::InvalidInput, e)))?;
    let descriptor = SecurityDescriptor::deserialize(&sddl).map_err(io_err)?;
    let name = path.to_fs_name::<GenericFilePath>().map_err(io_err)?;
    // Daemons started at the same moment take turns, and each looks before it creates: Wine
    // (where the tests run) ignores FILE_FLAG_FIRST_PIPE_INSTANCE and would hand a second
    // daemon instances of the first one's pipe.
    let _turn = StartMutex::take(path);
    // No waiting: a busy pipe exists, and is someone's.
    match connect_waiting(path, Duration::ZERO) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => {}
        found => return Err(taken(path, &sid, found)),
    }
    // interprocess creates the first instance with FILE_FLAG_FIRST_PIPE_INSTANCE, so on
    // Windows a name another process holds fails with ERROR_ACCESS_DENIED instead of adding
    // an instance to that process's pipe, even in a race with a process that does not take
    // the turn above; the later instances (one per accepted client) get this descriptor too.
    ListenerOptions::new()
        .name(name)
        .security_descriptor(descriptor)
        .create_sync()
        .map_err(|e| match e.raw_os_error().map(|c| c as u32) {
            Some(ERROR_ACCESS_DENIED | ERROR_PIPE_BUSY) => {
                taken(path, &sid, connect_unchecked(path))
            }
            _ => io_err(e),
        })
}

/// A named mutex `Local\tessd-bind-<pipe name>` held while [`bind`] looks for a live pipe
/// and creates its own (released on drop); nothing is held when it cannot be had (another
/// account's object of that name), FILE_FLAG_FIRST_PIPE_INSTANCE still decides then.
struct StartMutex(HANDLE);

impl StartMutex {
    fn take(pipe: &Path) -> Option<StartMutex> {
        use windows_sys::Win32::System::Threading::{CreateMutexW, INFINITE, WaitForSingleObject};
        // A mutex name may hold any character but a backslash.
        let name = format!(
            "Local\\tessd-bind-{}",
            pipe.to_string_lossy().replace('\\', "/").to_lowercase()
        );
        let name = widestring::U16CString::from_str(&name).ok()?;
        // SAFETY: a NUL-terminated name; no security attributes; not initially owned.
        let handle = unsafe { CreateMutexW(std::ptr::null(), 0, name.as_ptr()) };
        if handle.is_null() {
            log::warn!(
                "no start lock for {}: {}",
                pipe.display(),
                io::Error::last_os_error()
            );
            return None;
        }
        // SAFETY: a mutex handle we own; WAIT_ABANDONED (its holder died) also makes it ours.
        unsafe { WaitForSingleObject(handle, INFINITE) };
        Some(StartMutex(handle))
    }
}

impl Drop for StartMutex {
    fn drop(&mut self) {
        use windows_sys::Win32::System::Threading::ReleaseMutex;
        // SAFETY: the mutex is held by this thread and its handle is ours, closed once.
        unsafe {
            ReleaseMutex(self.0);
            CloseHandle(self.0);
        }
    }
}

/// Why the existing pipe `path` cannot be ours, from what connecting to it (`found`) gave: a
/// tessd of this user answers there ([`BindError::InUse`]), or another account holds the name
/// ([`BindError::Unsafe`]: a client would be talking to it).
fn taken(path: &Path, me: &UserSid, found: io::Result<Stream>) -> BindError {
    let foreign = |why: String| BindError::Unsafe {
        path: path.to_path_buf(),
        reason: format!("{why}; choose another --socket name"),
    };
    match found {
        Ok(stream) => match pipe_owner_is(&stream, me) {
            Ok(true) => BindError::InUse(path.to_path_buf()),
            Ok(false) => foreign("the pipe exists and belongs to another account".into()),
            Err(e) => foreign(format!(
                "the pipe exists and its owner cannot be read ({e})"
            )),
        },
        Err(e) if e.kind() == io::ErrorKind::PermissionDenied => {
            foreign("the pipe exists and this user may not open it (another account's)".into())
        }
        // All instances busy, or it went away in between: a live daemon, most likely.
        Err(_) => BindError::InUse(path.to_path_buf()),
    }
}

/// Connects to the pipe `path` and checks that this user owns it, so that requests (and the
/// meshes in them) never go to a pipe another account created under the daemon's name.
pub(super) fn connect(path: &Path) -> io::Result<Stream> {
    let stream = connect_unchecked(path)?;
    let me = UserSid::current()?;
    if !pipe_owner_is(&stream, &me)? {
        return Err(io::Error::new(
            io::ErrorKind::PermissionDenied,
            format!(
                "the pipe {} belongs to another account, not to this user; refusing to use it",
                path.display()
            ),
        ));
    }
    Ok(stream)
}

/// How long a client waits for a free instance of a busy pipe (between a connection and the
/// server's next instance, or while the server has not yet taken back a closed one).
const CONNECT_WAIT: Duration = Duration::from_secs(10);

fn connect_unchecked(path: &Path) -> io::Result<Stream> {
    connect_waiting(path, CONNECT_WAIT)
}

/// Connects to the pipe `path`, waiting at most `wait` for a free instance (`TimedOut` after
/// that; `NotFound` when no such pipe exists). interprocess's local-socket connect waits
/// without bound, which would hang a starting daemon on a stuck one.
fn connect_waiting(path: &Path, wait: Duration) -> io::Result<Stream> {
    use interprocess::ConnectWaitMode;
    use interprocess::os::windows::named_pipe::{DuplexPipeStream, pipe_mode};
    use std::os::windows::io::OwnedHandle;
    let pipe = DuplexPipeStream::<pipe_mode::Bytes>::connect_by_path_with_wait_mode(
        path,
        ConnectWaitMode::Timeout(wait),
    )?;
    let handle = OwnedHandle::try_from(pipe)
        .map_err(|_| io::Error::other("a named pipe stream without its handle"))?;
    let stream = interprocess::os::windows::named_pipe::local_socket::Stream::try_from(handle)
        .map_err(|_| io::Error::other("a pipe handle interprocess does not take"))?;
    Ok(Stream::from(stream))
}

/// The handle of a connected pipe stream.
fn raw_handle(stream: &Stream) -> HANDLE {
    let Stream::NamedPipe(s) = stream;
    s.as_handle().as_raw_handle()
}

/// Whether the pipe behind `stream` is owned by `sid`.
fn pipe_owner_is(stream: &Stream, sid: &UserSid) -> io::Result<bool> {
    let info = PipeSecurity::read(stream)?;
    // SAFETY: both SIDs are valid for the duration of the call.
    Ok(unsafe { EqualSid(info.owner, sid.as_psid()) } != 0)
}

/// An ACE as the tests see it: its type, access mask and SID (`S-1-5-...`).
#[cfg(test)]
type Ace = (u8, u32, String);

/// The owner and the ACEs (type, access mask, SID as `S-1-5-...`) of a connected pipe: what the
/// daemon's descriptor gave the pipe, read back from the kernel.
#[cfg(test)]
fn pipe_security(stream: &Stream) -> io::Result<(String, Vec<Ace>)> {
    use windows_sys::Win32::Security::{
        ACCESS_ALLOWED_ACE, ACE_HEADER, ACL_SIZE_INFORMATION, AclSizeInformation, GetAce,
        GetAclInformation,
    };
    use windows_sys::Win32::System::SystemServices::ACCESS_ALLOWED_ACE_TYPE;
    let info = PipeSecurity::read(stream)?;
    // SAFETY: `info.owner` is a valid SID inside `info`'s descriptor.
    let owner = unsafe { sid_string(info.owner) }?;
    let mut aces = Vec::new();
    if info.dacl.is_null() {
        // A null DACL grants everyone everything: report it as such.
        aces.push((ACCESS_ALLOWED_ACE_TYPE as u8, u32::MAX, "NULL DACL".into()));
        return Ok((owner, aces));
    }
    let mut size: ACL_SIZE_INFORMATION = unsafe { std::mem::zeroed() };
    // SAFETY: `info.dacl` is a valid ACL; `size` is writable and of the stated length.
    let ok = unsafe {
        GetAclInformation(
            info.dacl,
            (&raw mut size).cast(),
            size_of::<ACL_SIZE_INFORMATION>() as u32,
            AclSizeInformation,
        )
    };
    if ok == 0 {
        return Err(io::Error::last_os_error());
    }
    for i in 0..size.AceCount {
        let mut ace: *mut core::ffi::c_void = std::ptr::null_mut();
        // SAFETY: `i` is below the ACL's ACE count.
        if unsafe { GetAce(info.dacl, i, &mut ace) } == 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: every ACE starts with an ACE_HEADER.
        let header = unsafe { *(ace as *const ACE_HEADER) };
        let (mask, sid) =
            if u32::from(header.AceType) == ACCESS_ALLOWED_ACE_TYPE || header.AceType == 1 {
                // ACCESS_ALLOWED_ACE and ACCESS_DENIED_ACE share one layout.
                let a = ace as *const ACCESS_ALLOWED_ACE;
                // SAFETY: the ACE is of a type with this layout; its SID starts at SidStart.
                unsafe { ((*a).Mask, sid_string((&raw const (*a).SidStart) as PSID)?) }
            } else {
                (0, format!("(ACE type {})", header.AceType))
            };
        aces.push((header.AceType, mask, sid));
    }
    Ok((owner, aces))
}

/// The current user's SID as a string `S-1-5-...`.
#[cfg(test)]
fn current_user_sid() -> io::Result<String> {
    UserSid::current()?.to_string()
}

/// A pipe's owner and DACL, read from its handle (the descriptor is freed on drop).
struct PipeSecurity {
    owner: PSID,
    #[cfg_attr(not(test), allow(dead_code))] // read back by the tests
    dacl: *mut ACL,
    descriptor: PSECURITY_DESCRIPTOR,
}

impl PipeSecurity {
    fn read(stream: &Stream) -> io::Result<PipeSecurity> {
        let mut owner: PSID = std::ptr::null_mut();
        let mut dacl: *mut ACL = std::ptr::null_mut();
        let mut descriptor: PSECURITY_DESCRIPTOR = std::ptr::null_mut();
        // SAFETY: the handle is a live pipe handle opened with read access (READ_CONTROL);
        // the out pointers are writable; the descriptor is freed with LocalFree on drop.
        let rc = unsafe {
            GetSecurityInfo(
                raw_handle(stream),
                SE_KERNEL_OBJECT,
                OWNER_SECURITY_INFORMATION | DACL_SECURITY_INFORMATION,
                &mut owner,
                std::ptr::null_mut(),
                &mut dacl,
                std::ptr::null_mut(),
                &mut descriptor,
            )
        };
        if rc != 0 {
            return Err(io::Error::from_raw_os_error(rc as i32));
        }
        if owner.is_null() {
            // SAFETY: allocated by GetSecurityInfo.
            unsafe { LocalFree(descriptor as HLOCAL) };
            return Err(io::Error::other("the pipe has no owner"));
        }
        Ok(PipeSecurity {
            owner,
            dacl,
            descriptor,
        })
    }
}

impl Drop for PipeSecurity {
    fn drop(&mut self) {
        // SAFETY: allocated by GetSecurityInfo, freed once.
        unsafe { LocalFree(self.descriptor as HLOCAL) };
    }
}

/// The user SID of this process's token (in a buffer that holds the `TOKEN_USER`).
struct UserSid(Vec<u64>);

impl UserSid {
    fn current() -> io::Result<UserSid> {
        let mut token: HANDLE = std::ptr::null_mut();
        // SAFETY: the pseudo handle of this process; `token` is writable.
        if unsafe { OpenProcessToken(GetCurrentProcess(), TOKEN_QUERY, &mut token) } == 0 {
            return Err(io::Error::last_os_error());
        }
        let result = (|| {
            let mut len = 0u32;
            // SAFETY: a size query: no buffer, `len` receives the size needed.
            unsafe { GetTokenInformation(token, TokenUser, std::ptr::null_mut(), 0, &mut len) };
            // SAFETY: reads this thread's last error.
            if unsafe { GetLastError() } != ERROR_INSUFFICIENT_BUFFER {
                return Err(io::Error::last_os_error());
            }
            let mut buf = vec![0u64; (len as usize).div_ceil(8)];
            // SAFETY: `buf` holds at least `len` bytes, aligned for TOKEN_USER.
            let ok = unsafe {
                GetTokenInformation(token, TokenUser, buf.as_mut_ptr().cast(), len, &mut len)
            };
            if ok == 0 {
                return Err(io::Error::last_os_error());
            }
            Ok(UserSid(buf))
        })();
        // SAFETY: `token` is ours and closed once.
        unsafe { CloseHandle(token) };
        result
    }

    fn as_psid(&self) -> PSID {
        // SAFETY: the buffer holds a TOKEN_USER filled by GetTokenInformation.
        unsafe { (*(self.0.as_ptr() as *const TOKEN_USER)).User.Sid }
    }

    fn to_string(&self) -> io::Result<String> {
        // SAFETY: a valid SID inside the token buffer.
        unsafe { sid_string(self.as_psid()) }
    }
}

/// `sid` as `S-1-5-...`.
///
/// # Safety
/// `sid` must point to a valid SID.
unsafe fn sid_string(sid: PSID) -> io::Result<String> {
    let mut text: *mut u16 = std::ptr::null_mut();
    // SAFETY: the caller guarantees `sid`; `text` receives a LocalAlloc'd string.
    if unsafe { ConvertSidToStringSidW(sid, &mut text) } == 0 {
        return Err(io::Error::last_os_error());
    }
    // SAFETY: a NUL-terminated wide string from ConvertSidToStringSidW, freed once after.
    let s = unsafe { widestring::U16CStr::from_ptr_str(text) }.to_string_lossy();
    unsafe { LocalFree(text as HLOCAL) };
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use interprocess::local_socket::traits::Listener as _;

    /// A pipe name no other test (or test process) uses.
    fn fresh_pipe(tag: &str) -> std::path::PathBuf {
        static N: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        format!(r"\\.\pipe\tessd-ipc-test-{}-{n}-{tag}", std::process::id()).into()
    }

    #[test]
    fn the_pipe_admits_only_its_user() {
        let path = fresh_pipe("dacl");
        let listener = super::super::bind(&path).unwrap();
        let server = std::thread::spawn(move || listener.accept().map(|_| ()));
        let stream = connect(&path).unwrap();
        let (owner, aces) = pipe_security(&stream).unwrap();
        let me = current_user_sid().unwrap();
        println!("user {me}; pipe owner {owner}; DACL {aces:?}");
        assert_eq!(owner, me);
        // Exactly one ACE: access allowed (type 0) to this user, with full file access
        // (FILE_ALL_ACCESS = 0x1F01FF); no Everyone (S-1-1-0), Anonymous (S-1-5-7) or other SID.
        assert_eq!(aces, [(0u8, 0x001F_01FFu32, me)]);
        server.join().unwrap().unwrap();
    }

    #[test]
    fn a_second_bind_on_a_live_pipe_is_in_use() {
        let path = fresh_pipe("twice");
        let _first = super::super::bind(&path).unwrap();
        match super::super::bind(&path) {
            Err(BindError::InUse(p)) => assert_eq!(p, path),
            Err(e) => panic!("expected InUse, got {e}"),
            Ok(_) => panic!("a second listener on {}", path.display()),
        }
    }

    #[test]
    fn a_file_path_is_not_bound() {
        let dir = std::env::temp_dir().join("t.sock");
        match super::super::bind(&dir) {
            Err(BindError::Unsafe { reason, .. }) => {
                assert!(reason.contains("named pipe"), "{reason}")
            }
            Err(e) => panic!("expected a refusal, got {e}"),
            Ok(_) => panic!("bound at {}", dir.display()),
        }
        assert!(!dir.exists());
    }

    #[test]
    fn resolve_maps_names_to_pipes_and_refuses_file_paths() {
        let user = super::super::pipe_user(std::env::var_os("USERNAME").as_deref());
        let r = |v| super::super::resolve(v, true).map(|p| p.display().to_string());
        assert_eq!(r(None).unwrap(), format!(r"\\.\pipe\tessd-{user}"));
        assert_eq!(r(Some("w1")).unwrap(), format!(r"\\.\pipe\tessd-{user}-w1"));
        assert_eq!(r(Some(r"\\.\pipe\mine")).unwrap(), r"\\.\pipe\mine");
        for bad in [
            r"C:\x\t.sock",
            "C:/x/t.sock",
            r"\\server\share\t.sock",
            r"sub\t",
        ] {
            let e = r(Some(bad)).unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{bad}");
            assert!(e.to_string().contains(bad), "{e}");
        }
    }

    #[test]
    fn a_pipe_another_account_owns_is_neither_served_nor_used() {
        // A squatter's pipe: owned by another SID (the Administrators group, an owner this
        // token may set under Wine), open to Everyone.
        let path = fresh_pipe("squat");
        let sddl = widestring::U16CString::from_str("O:BAD:(A;;FA;;;WD)").unwrap();
        let squatter = ListenerOptions::new()
            .name(path.as_path().to_fs_name::<GenericFilePath>().unwrap())
            .security_descriptor(SecurityDescriptor::deserialize(&sddl).unwrap())
            .create_sync()
            .unwrap();
        // Accepts whatever comes, for as long as the test process lives (not joined: how many
        // connections reach an accept depends on when the clients close).
        std::thread::spawn(move || while squatter.accept().is_ok() {});
        match super::super::bind(&path) {
            Err(BindError::Unsafe { reason, .. }) => {
                assert!(reason.contains("belongs to another account"), "{reason}")
            }
            Err(e) => panic!("expected a refusal, got {e}"),
            Ok(_) => panic!("served a squatted pipe {}", path.display()),
        }
        let e = connect(&path).expect_err("a client used the squatter's pipe");
        assert_eq!(e.kind(), io::ErrorKind::PermissionDenied, "{e}");
        assert!(e.to_string().contains("another account"), "{e}");
    }
}
