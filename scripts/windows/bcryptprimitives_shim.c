/*
 * TEST HARNESS ONLY - never shipped, never bundled with tessd.exe.
 *
 * Rust's standard library on Windows imports `ProcessPrng` from `bcryptprimitives.dll` (its
 * source of randomness, e.g. for HashMap keys). Wine 8 has no such DLL, so every Rust program
 * fails to start under it. This DLL exports `ProcessPrng` over advapi32's `SystemFunction036`
 * (RtlGenRandom), which Wine implements. Real Windows (10 and later) has the real DLL; this
 * shim exists only so the Rust tests can run under Wine in CI.
 *
 * scripts/windows/wine-run.sh builds it with mingw into the private Wine prefix's system32
 * (never beside the executables in the target folder):
 *   x86_64-w64-mingw32-gcc -shared -o bcryptprimitives.dll bcryptprimitives_shim.c -ladvapi32
 */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T len) {
    /* SystemFunction036 takes a ULONG length: feed larger requests in pieces. */
    while (len > 0) {
        ULONG chunk = len > 0x40000000 ? 0x40000000 : (ULONG)len;
        if (!SystemFunction036(data, chunk)) {
            return FALSE;
        }
        data += chunk;
        len -= chunk;
    }
    return TRUE;
}
