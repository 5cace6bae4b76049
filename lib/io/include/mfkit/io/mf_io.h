/*
 * mf_io.h -- the file helpers every mfkit writer uses: a growable byte buffer, "path: reason"
 * messages, reading a whole file, and the one atomic file write.
 *
 * Atomic writes.  A file is never written in place: the bytes go to a fresh temporary file in
 * the target's directory, named "<path>.tmp<pid>_<n>" (created exclusively, so concurrent
 * writers never share one), which is flushed, fsync'ed and closed -- every step checked -- and
 * then renamed over the target.  On any failure the temporary is removed and the target is
 * neither created nor changed; the status is MF_ERR_IO (MF_ERR_ALLOC when memory ran out) and
 * the message says which step failed and why ("out.exr: cannot write temporary file
 * out.exr.tmp123_0: File too large").
 *
 * Plain C11 (fsync and getpid where POSIX has them).
 */
#ifndef MF_IO_H
#define MF_IO_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <mfkit/mf_core.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- growable byte buffer ------------------------------------------------------------------ */

/* Zero-initialise ({0}).  After an allocation failure `failed` is set and later appends are
 * dropped, so a writer appends freely and checks `failed` once (mf_io_write_atomic does). */
typedef struct mf_buf {
    char *data;
    size_t len, cap;
    int failed;
} mf_buf;

void mf_buf_put(mf_buf *b, const void *data, size_t n);
void mf_buf_puts(mf_buf *b, const char *s);
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
void mf_buf_printf(mf_buf *b, const char *fmt, ...);
void mf_buf_vprintf(mf_buf *b, const char *fmt, va_list ap);
/* Makes room for n more bytes (0 after an allocation failure). */
int mf_buf_reserve(mf_buf *b, size_t n);
/* Little-endian integers and float32. */
void mf_buf_u16le(mf_buf *b, uint16_t v);
void mf_buf_u32le(mf_buf *b, uint32_t v);
void mf_buf_f32le(mf_buf *b, float v);
/* Frees the memory and zeroes the buffer (NULL and zeroed buffers accepted). */
void mf_buf_free(mf_buf *b);

/* ---- messages ------------------------------------------------------------------------------ */

/* "path: reason" into msg (may be NULL, or msg_size 0), on one line: newlines become spaces. */
#if defined(__GNUC__)
__attribute__((format(printf, 4, 5)))
#endif
void mf_io_msg(char *msg, size_t msg_size, const char *path, const char *fmt, ...);
/* The same with the arguments in ap. */
void mf_io_vmsg(char *msg, size_t msg_size, const char *path, const char *fmt, va_list ap);
/* Empties msg (if not NULL). */
void mf_io_msg_clear(char *msg, size_t msg_size);

/* ---- reading ------------------------------------------------------------------------------- */

/* Files larger than this are refused by mf_io_read_file (MF_ERR_FORMAT), not read. */
#define MF_IO_MAX_FILE_BYTES ((size_t)1 << 30)

/*
 * Reads the whole file into a malloc'd buffer with a NUL after the data (free it).
 *   msg_path   the name used in messages (NULL: path), e.g. the data file of a sidecar.
 *   missing    may be NULL; set (without a message) when the file does not exist.
 * Returns MF_OK; MF_ERR_IO (cannot open or read); MF_ERR_FORMAT (larger than
 * MF_IO_MAX_FILE_BYTES); MF_ERR_ALLOC.
 */
mf_status mf_io_read_file(const char *path, const char *msg_path, unsigned char **data, size_t *len, int *missing,
                          char *msg, size_t msg_size) MF_WARN_UNUSED;

/* ---- directories -------------------------------------------------------------------------- */

/* mkdir -p: creates dir and its missing parents (mode 0777 less the umask).  MF_OK if dir is
 * (now) a directory; MF_ERR_IO with "dir: cannot create the directory: reason" (a path that
 * exists as a file: "Not a directory"); MF_ERR_UNSUPPORTED where POSIX is missing. */
mf_status mf_io_make_dirs(const char *dir, char *msg, size_t msg_size) MF_WARN_UNUSED;

/* ---- the atomic write ---------------------------------------------------------------------- */

/* Writes len bytes to path atomically (see above). */
mf_status mf_io_write_atomic(const char *path, const void *data, size_t len, char *msg, size_t msg_size)
    MF_WARN_UNUSED;
/* mf_io_write_atomic of a buffer: MF_ERR_ALLOC ("path: out of memory") if b->failed. */
mf_status mf_io_write_buf_atomic(const char *path, const mf_buf *b, char *msg, size_t msg_size) MF_WARN_UNUSED;

/*
 * The same transaction in steps, for writers that stream to a FILE or that write the temporary
 * by name (an image library):
 *   mf_io_atomic_begin   creates the temporary; a->file is open for writing ("wb") and
 *                        a->tmp_path names it.  A writer that writes by name may fclose(a->file)
 *                        and set it to NULL first.
 *   mf_io_atomic_commit  flushes, fsyncs and closes a->file (or, if it is NULL, fsyncs the
 *                        temporary by name), checks every step, renames; on failure removes the
 *                        temporary.  Always releases a.
 *   mf_io_atomic_finish  the flush/fsync/close part of commit alone (the rename left for
 *                        commit), so that several files can all be written before any replaces
 *                        its target; on failure removes the temporary and releases a.
 *   mf_io_atomic_abort   closes and removes the temporary; releases a.  Safe on a released or
 *                        zeroed a.
 */
typedef struct mf_io_atomic {
    FILE *file;
    char *path;     /* copy of the target */
    char *tmp_path; /* the temporary */
    int finished;   /* mf_io_atomic_finish succeeded */
} mf_io_atomic;

mf_status mf_io_atomic_begin(mf_io_atomic *a, const char *path, char *msg, size_t msg_size) MF_WARN_UNUSED;
mf_status mf_io_atomic_finish(mf_io_atomic *a, char *msg, size_t msg_size) MF_WARN_UNUSED;
mf_status mf_io_atomic_commit(mf_io_atomic *a, char *msg, size_t msg_size) MF_WARN_UNUSED;
void mf_io_atomic_abort(mf_io_atomic *a);

/*
 * Several files committed together (all or nothing), e.g. a data file and its sidecar, or every
 * level of a MIP chain: begin and write each, then
 *   mf_io_atomic_commit_all  finishes every temporary (flush, fsync, close) before any rename, so
 *                            a full disk or a write error leaves no target changed; then renames
 *                            them in order.  If a rename fails (the directory removed or made
 *                            read-only midway), the targets already renamed are removed, so that
 *                            no mix of files from two runs is left.  Always releases every a[i].
 *   mf_io_atomic_abort_all   mf_io_atomic_abort of each (zeroed or released entries accepted).
 */
mf_status mf_io_atomic_commit_all(mf_io_atomic *a, size_t n, char *msg, size_t msg_size) MF_WARN_UNUSED;
void mf_io_atomic_abort_all(mf_io_atomic *a, size_t n);

#ifdef __cplusplus
}
#endif
#endif /* MF_IO_H */
