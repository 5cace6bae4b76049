/* mf_io.c -- the byte buffer, messages, whole-file reads and the one atomic write (mf_io.h). */
#if defined(__unix__) || defined(__APPLE__)
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#define MF_IO_POSIX 1
#endif

#include "mfkit/io/mf_io.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#if defined(__STDC_NO_ATOMICS__)
static unsigned long temp_counter;
#define NEXT_TEMP() (temp_counter++)
#else
#include <stdatomic.h>
static atomic_ulong temp_counter;
#define NEXT_TEMP() atomic_fetch_add(&temp_counter, 1ul)
#endif

/* ---- buffer -------------------------------------------------------------------------------- */

int mf_buf_reserve(mf_buf *b, size_t add)
{
    if (b->failed)
        return 0;
    if (add <= b->cap - b->len)
        return 1;
    size_t cap = b->cap ? b->cap : 4096;
    while (cap - b->len < add) {
        if (cap > SIZE_MAX / 2) {
            b->failed = 1;
            return 0;
        }
        cap *= 2;
    }
    char *p = realloc(b->data, cap);
    if (!p) {
        b->failed = 1;
        return 0;
    }
    b->data = p;
    b->cap = cap;
    return 1;
}

void mf_buf_put(mf_buf *b, const void *data, size_t n)
{
    if (n && mf_buf_reserve(b, n)) {
        memcpy(b->data + b->len, data, n);
        b->len += n;
    }
}

void mf_buf_puts(mf_buf *b, const char *s) { mf_buf_put(b, s, strlen(s)); }

void mf_buf_vprintf(mf_buf *b, const char *fmt, va_list ap)
{
    char small[256];
    va_list ap2;
    va_copy(ap2, ap);
    int n = vsnprintf(small, sizeof small, fmt, ap);
    if (n < 0) {
        b->failed = 1;
    } else if ((size_t)n < sizeof small) {
        mf_buf_put(b, small, (size_t)n);
    } else if (mf_buf_reserve(b, (size_t)n + 1)) {
        vsnprintf(b->data + b->len, (size_t)n + 1, fmt, ap2);
        b->len += (size_t)n;
    }
    va_end(ap2);
}

void mf_buf_printf(mf_buf *b, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    mf_buf_vprintf(b, fmt, ap);
    va_end(ap);
}

void mf_buf_u16le(mf_buf *b, uint16_t v)
{
    unsigned char c[2] = {(unsigned char)(v & 0xff), (unsigned char)(v >> 8)};
    mf_buf_put(b, c, 2);
}

void mf_buf_u32le(mf_buf *b, uint32_t v)
{
    unsigned char c[4] = {(unsigned char)(v & 0xff), (unsigned char)((v >> 8) & 0xff),
                          (unsigned char)((v >> 16) & 0xff), (unsigned char)(v >> 24)};
    mf_buf_put(b, c, 4);
}

void mf_buf_f32le(mf_buf *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    mf_buf_u32le(b, u);
}

void mf_buf_free(mf_buf *b)
{
    if (!b)
        return;
    free(b->data);
    memset(b, 0, sizeof *b);
}

/* ---- messages ------------------------------------------------------------------------------ */

void mf_io_vmsg(char *msg, size_t msg_size, const char *path, const char *fmt, va_list ap)
{
    if (!msg || msg_size == 0)
        return;
    int n = snprintf(msg, msg_size, "%s: ", path ? path : "(null)");
    if (n < 0 || (size_t)n >= msg_size)
        return;
    vsnprintf(msg + n, msg_size - (size_t)n, fmt, ap);
    for (char *c = msg; *c; ++c)
        if (*c == '\n' || *c == '\r')
            *c = ' ';
}

void mf_io_msg(char *msg, size_t msg_size, const char *path, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    mf_io_vmsg(msg, msg_size, path, fmt, ap);
    va_end(ap);
}

void mf_io_msg_clear(char *msg, size_t msg_size)
{
    if (msg && msg_size)
        msg[0] = '\0';
}

/* ---- reading ------------------------------------------------------------------------------- */

mf_status mf_io_read_file(const char *path, const char *msg_path, unsigned char **data, size_t *len, int *missing,
                          char *msg, size_t msg_size)
{
    *data = NULL;
    *len = 0;
    if (missing)
        *missing = 0;
    if (!msg_path)
        msg_path = path;
    errno = 0;
    FILE *f = fopen(path, "rb");
    if (!f) {
        int err = errno;
        if (missing && err == ENOENT) {
            *missing = 1;
            return MF_ERR_IO;
        }
        if (strcmp(path, msg_path) == 0)
            mf_io_msg(msg, msg_size, msg_path, "cannot open: %s", err ? strerror(err) : "unknown error");
        else
            mf_io_msg(msg, msg_size, msg_path, "cannot open %s: %s", path, err ? strerror(err) : "unknown error");
        return MF_ERR_IO;
    }
    size_t cap = 1 << 16, n = 0;
    unsigned char *buf = malloc(cap + 1);
    if (!buf) {
        fclose(f);
        mf_io_msg(msg, msg_size, msg_path, "out of memory");
        return MF_ERR_ALLOC;
    }
    for (;;) {
        if (n == cap) {
            if (cap >= MF_IO_MAX_FILE_BYTES) {
                free(buf);
                fclose(f);
                mf_io_msg(msg, msg_size, msg_path, "file larger than %zu bytes", MF_IO_MAX_FILE_BYTES);
                return MF_ERR_FORMAT;
            }
            size_t nc = cap * 2;
            unsigned char *p = realloc(buf, nc + 1);
            if (!p) {
                free(buf);
                fclose(f);
                mf_io_msg(msg, msg_size, msg_path, "out of memory");
                return MF_ERR_ALLOC;
            }
            buf = p;
            cap = nc;
        }
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0)
            break;
    }
    int bad = ferror(f);
    int err = errno;
    fclose(f);
    if (bad) {
        free(buf);
        mf_io_msg(msg, msg_size, msg_path, "read error: %s", err ? strerror(err) : "unknown error");
        return MF_ERR_IO;
    }
    buf[n] = '\0';
    *data = buf;
    *len = n;
    return MF_OK;
}

/* ---- directories -------------------------------------------------------------------------- */

mf_status mf_io_make_dirs(const char *dir, char *msg, size_t msg_size)
{
#ifdef MF_IO_POSIX
    size_t n = dir ? strlen(dir) : 0;
    if (n == 0) {
        mf_io_msg(msg, msg_size, dir, "invalid argument (NULL or empty directory)");
        return MF_ERR_DOMAIN;
    }
    char *path = malloc(n + 1);
    if (!path) {
        mf_io_msg(msg, msg_size, dir, "out of memory");
        return MF_ERR_ALLOC;
    }
    memcpy(path, dir, n + 1);
    int err = 0;
    for (size_t i = 1; i <= n && !err; ++i)
        if (path[i] == '/' || path[i] == '\0') {
            char c = path[i];
            path[i] = '\0';
            if (mkdir(path, 0777) != 0 && errno != EEXIST)
                err = errno;
            path[i] = c;
        }
    free(path);
    struct stat st;
    if (!err && stat(dir, &st) != 0)
        err = errno;
    if (!err && !S_ISDIR(st.st_mode))
        err = ENOTDIR;
    if (err) {
        mf_io_msg(msg, msg_size, dir, "cannot create the directory: %s", strerror(err));
        return MF_ERR_IO;
    }
    return MF_OK;
#else
    mf_io_msg(msg, msg_size, dir, "creating directories needs POSIX");
    return MF_ERR_UNSUPPORTED;
#endif
}

/* ---- the atomic write ---------------------------------------------------------------------- */

static void atomic_release(mf_io_atomic *a)
{
    free(a->path);
    free(a->tmp_path);
    memset(a, 0, sizeof *a);
}

mf_status mf_io_atomic_begin(mf_io_atomic *a, const char *path, char *msg, size_t msg_size)
{
    memset(a, 0, sizeof *a);
    if (!path || !*path) {
        mf_io_msg(msg, msg_size, path, "invalid argument (NULL or empty path)");
        return MF_ERR_DOMAIN;
    }
    size_t n = strlen(path);
    a->path = malloc(n + 1);
    a->tmp_path = malloc(n + 64);
    if (!a->path || !a->tmp_path) {
        atomic_release(a);
        mf_io_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    memcpy(a->path, path, n + 1);
    unsigned long pid = 0;
#ifdef MF_IO_POSIX
    pid = (unsigned long)getpid();
#endif
    for (int attempt = 0; attempt < 100; ++attempt) {
        snprintf(a->tmp_path, n + 64, "%s.tmp%lu_%lu", path, pid, NEXT_TEMP());
        errno = 0;
        a->file = fopen(a->tmp_path, "wbx"); /* C11 exclusive mode: never reuse an existing file */
        if (a->file || errno != EEXIST)
            break;
    }
    if (!a->file) {
        int err = errno;
        mf_io_msg(msg, msg_size, path, "cannot create temporary file %s: %s", a->tmp_path,
                  err ? strerror(err) : "unknown error");
        atomic_release(a);
        return MF_ERR_IO;
    }
    return MF_OK;
}

void mf_io_atomic_abort(mf_io_atomic *a)
{
    if (!a)
        return;
    if (a->file)
        fclose(a->file);
    if (a->tmp_path)
        remove(a->tmp_path);
    atomic_release(a);
}

mf_status mf_io_atomic_finish(mf_io_atomic *a, char *msg, size_t msg_size)
{
    if (!a->tmp_path) {
        mf_io_msg(msg, msg_size, a->path, "internal error: no temporary file");
        mf_io_atomic_abort(a);
        return MF_ERR_INTERNAL;
    }
    if (a->finished)
        return MF_OK;
    int ok = 1, err = 0;
    if (a->file) {
        errno = 0;
        if (ferror(a->file) || fflush(a->file) != 0) {
            ok = 0;
            err = errno;
        }
#ifdef MF_IO_POSIX
        if (ok && fsync(fileno(a->file)) != 0) {
            ok = 0;
            err = errno;
        }
#endif
        errno = 0;
        if (fclose(a->file) != 0 && ok) {
            ok = 0;
            err = errno;
        }
        a->file = NULL;
    } else {
#ifdef MF_IO_POSIX
        /* written by name: flush the data to disk through a descriptor of our own */
        int fd = open(a->tmp_path, O_RDONLY);
        if (fd < 0 || fsync(fd) != 0) {
            ok = 0;
            err = errno;
        }
        if (fd >= 0)
            close(fd);
#endif
    }
    if (!ok) {
        mf_io_msg(msg, msg_size, a->path, "cannot write temporary file %s: %s", a->tmp_path,
                  err ? strerror(err) : "write error");
        mf_io_atomic_abort(a);
        return MF_ERR_IO;
    }
    a->finished = 1;
    return MF_OK;
}

mf_status mf_io_atomic_commit(mf_io_atomic *a, char *msg, size_t msg_size)
{
    mf_status st = mf_io_atomic_finish(a, msg, msg_size);
    if (st != MF_OK)
        return st;
    if (rename(a->tmp_path, a->path) != 0) {
        int err = errno;
        mf_io_msg(msg, msg_size, a->path, "cannot rename %s to it: %s", a->tmp_path, strerror(err));
        mf_io_atomic_abort(a);
        return MF_ERR_IO;
    }
    atomic_release(a);
    return MF_OK;
}

void mf_io_atomic_abort_all(mf_io_atomic *a, size_t n)
{
    for (size_t i = 0; a && i < n; ++i)
        mf_io_atomic_abort(&a[i]);
}

mf_status mf_io_atomic_commit_all(mf_io_atomic *a, size_t n, char *msg, size_t msg_size)
{
    for (size_t i = 0; i < n; ++i) {
        mf_status st = mf_io_atomic_finish(&a[i], msg, msg_size);
        if (st != MF_OK) {
            mf_io_atomic_abort_all(a, n);
            return st;
        }
    }
    for (size_t i = 0; i < n; ++i) {
        if (rename(a[i].tmp_path, a[i].path) != 0) {
            int err = errno;
            mf_io_msg(msg, msg_size, a[i].path, "cannot rename %s to it: %s", a[i].tmp_path, strerror(err));
            for (size_t k = 0; k < i; ++k)
                remove(a[k].path);
            mf_io_atomic_abort_all(a, n);
            return MF_ERR_IO;
        }
        /* renamed: nothing left to remove on a later failure but the target itself */
        free(a[i].tmp_path);
        a[i].tmp_path = NULL;
    }
    for (size_t i = 0; i < n; ++i)
        atomic_release(&a[i]);
    return MF_OK;
}

mf_status mf_io_write_atomic(const char *path, const void *data, size_t len, char *msg, size_t msg_size)
{
    mf_io_atomic a;
    mf_status st = mf_io_atomic_begin(&a, path, msg, msg_size);
    if (st != MF_OK)
        return st;
    errno = 0;
    if (len && fwrite(data, 1, len, a.file) != len) {
        int err = errno;
        mf_io_msg(msg, msg_size, path, "cannot write temporary file %s: %s", a.tmp_path,
                  err ? strerror(err) : "write error");
        mf_io_atomic_abort(&a);
        return MF_ERR_IO;
    }
    return mf_io_atomic_commit(&a, msg, msg_size);
}

mf_status mf_io_write_buf_atomic(const char *path, const mf_buf *b, char *msg, size_t msg_size)
{
    if (b->failed) {
        mf_io_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    return mf_io_write_atomic(path, b->data, b->len, msg, msg_size);
}
