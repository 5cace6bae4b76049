/*
 * mf_image.h -- read and write float images: a plain C dispatcher over an image backend.
 *
 * Backends.  mfkit_io itself reads and writes no image format: a program installs a backend
 * once, before its first image call, with mf_image_set_backend.  The OpenImageIO backend (target
 * mfkit_image_oiio, header mfkit/fit/mf_image_oiio.h) is installed by
 *
 *     mf_image_set_backend(mf_image_oiio_backend());
 *
 * Without a backend every read and write returns MF_ERR_UNSUPPORTED with
 * "path: reading EXR needs the OpenImageIO build" (or "writing", and the file's extension), so a
 * pure C build handles every other table format and reports images cleanly.  Installing is not
 * automatic: a static library's object is linked only when referenced, and a program that does
 * not need images should not load the image stack.
 *
 * Writes are atomic (mf_io.h): the dispatcher creates the temporary "<path>.tmp<pid>_<n>", the
 * backend writes it by name in the format of path's extension, and the dispatcher fsyncs and
 * renames it; on any failure the temporary is removed and path is neither created nor changed.
 *
 * An mf_image is a 2D array of float pixels, row-major from the top row, channels interleaved:
 * channel c of pixel (x, y) is pixels[((size_t)y * width + x) * channels + c].  Values are
 * stored and returned as they are: no colour-space conversion and no alpha (un)premultiplication.
 *
 * Every function here is plain C; the C++ implementation catches every exception at the
 * boundary and never prints.  Error messages are written into a caller buffer as
 * "path: reason" (reason from OpenImageIO's geterror(), or from the C library for file system
 * errors), NUL-terminated and truncated to fit.  msg may be NULL or msg_size 0 for no message;
 * on success msg is set to the empty string.
 */
#ifndef MF_IMAGE_H
#define MF_IMAGE_H

#include <stddef.h>
#include <stdint.h>

#include <mfkit/mf_core.h>
#include <mfkit/io/mf_io.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mf_image {
    int width, height, channels; /* in pixels, pixels and channels per pixel; all >= 1 when valid */
    float *pixels;               /* width * height * channels floats, row-major, interleaved; owned by
                                  * the image when filled by mf_image_read (free with mf_image_free) */
} mf_image;

/* ---- backends ------------------------------------------------------------------------------- */

struct mf_image_write_options;
struct mf_image_info;

typedef struct mf_image_backend {
    const char *name; /* e.g. "OpenImageIO 2.4" */
    /* mf_image_read_ex: arguments checked, *out and *info (if not NULL) zeroed, msg cleared.
     * Pixels and info strings are allocated with malloc (mf_image_free / mf_image_info_free free
     * them with free). */
    mf_status (*read)(const char *path, struct mf_image *out, const char *attrib_name, struct mf_image_info *info,
                      char *msg, size_t msg_size);
    /* Writes img to the file tmp_path (which exists, empty), in the format of path's extension,
     * and closes it, reporting every failure (messages name path).  Arguments checked. */
    mf_status (*write)(const char *path, const char *tmp_path, const struct mf_image *img,
                       const struct mf_image_write_options *opt, char *msg, size_t msg_size);
} mf_image_backend;

/* Installs the backend every later call uses (NULL: none).  The struct must outlive its use.
 * Thread-safe, but meant to be called once at start-up. */
void mf_image_set_backend(const mf_image_backend *backend);
/* The installed backend, or NULL. */
const mf_image_backend *mf_image_get_backend(void);

/*
 * Read the first subimage (MIP level 0, its data window) of any file OpenImageIO can read, with
 * every channel converted to float (integer formats map to [0, 1] as OpenImageIO does).
 *   path          the file name (UTF-8).
 *   out           out: the image; its previous contents are overwritten, not freed.  On failure
 *                 *out is zeroed (width = height = channels = 0, pixels = NULL).
 *   msg, msg_size a buffer for "path: reason" on failure.
 * Returns MF_OK; MF_ERR_DOMAIN (path or out NULL); MF_ERR_IO (the file cannot be opened, e.g. it
 * does not exist or is not readable); MF_ERR_FORMAT (OpenImageIO cannot read it: unknown, corrupt
 * or truncated file); MF_ERR_UNSUPPORTED (no image backend, or a deep or volume image); MF_ERR_ALLOC; MF_ERR_INTERNAL
 * (an unexpected exception).  Corrupt or truncated files give an error, never a crash.
 */
mf_status mf_image_read(const char *path, mf_image *out, char *msg, size_t msg_size) MF_WARN_UNUSED;

/*
 * Write img to path, the format chosen from the file name's extension (.exr, .tif, .png, ...).
 *   img           a valid image (width, height, channels >= 1, pixels non-NULL); not modified.
 *                 Channels are named R, G, B, A for 1 to 4 channels (1 channel: Y), further ones
 *                 by OpenImageIO's defaults.
 *   half_float    non-zero: store 16-bit half floats where the format has them (OpenEXR; relative
 *                 rounding error <= 2^-11 for magnitudes in [2^-14, 65504], larger magnitudes
 *                 become infinite); zero: 32-bit floats (lossless).  Formats without half storage
 *                 get the nearest pixel type they support: TIFF stores floats, PNG and JPEG
 *                 quantise to integers (and JPEG is lossy).
 *   msg, msg_size a buffer for "path: reason" on failure.
 * The write is atomic (see the top of this file).
 * Returns MF_OK; MF_ERR_DOMAIN (a NULL or invalid argument); MF_ERR_UNSUPPORTED (no backend, no writer for
 * the extension, or the format cannot store this image, e.g. 5 channels in PNG); MF_ERR_IO (the
 * temporary file cannot be created, written or renamed, e.g. the directory does not exist);
 * MF_ERR_ALLOC; MF_ERR_INTERNAL (an unexpected exception).
 */
mf_status mf_image_write(const char *path, const mf_image *img, int half_float, char *msg, size_t msg_size)
    MF_WARN_UNUSED;

/*
 * What mf_image_read_ex reports besides the pixels.  Owned by the caller after a successful read;
 * release with mf_image_info_free.
 */
typedef struct mf_image_info {
    char **channel_names; /* `channels` NUL-terminated names in the order of the returned pixels
                           * (OpenEXR stores channels sorted by name, and OpenImageIO may reorder
                           * them, e.g. R, G, B, A first: match channels by name, not position) */
    int nchannels;        /* entries of channel_names (the image's channel count) */
    char *attrib_value;   /* the string attribute asked for, or NULL if the file has none */
    char pixel_type[16];  /* how the file stores samples, OpenImageIO's name: "half", "float", "uint8" */
} mf_image_info;

/*
 * mf_image_read, plus the channel names, the stored pixel type and one string attribute of the
 * file's header (attrib_name, e.g. "mfkit:table"; NULL for none).  info may be NULL (then this is
 * mf_image_read).  On failure *info is zeroed (nothing to free).  Same status codes as
 * mf_image_read.
 */
mf_status mf_image_read_ex(const char *path, mf_image *out, const char *attrib_name, mf_image_info *info, char *msg,
                           size_t msg_size) MF_WARN_UNUSED;
void mf_image_info_free(mf_image_info *info); /* NULL and zeroed infos are accepted */

/*
 * Options of mf_image_write_ex.  A zeroed struct gives mf_image_write(path, img, 0, ...).
 */
typedef struct mf_image_write_options {
    int half_float;                    /* as mf_image_write */
    const uint16_t *half_bits;         /* with half_float: NULL, or the IEEE binary16 bit patterns to
                                        * store (same layout as img->pixels, which may then be NULL),
                                        * written as given, so the caller controls the float -> half
                                        * rounding; ignored without half_float */
    const char *const *channel_names;  /* NULL (defaults as mf_image_write), or img->channels non-empty
                                        * distinct names; no channel is then treated as alpha */
    int nattribs;                      /* string attributes for the file header (OpenEXR: string
                                        * attributes under these names; formats without free-form
                                        * metadata drop them) */
    const char *const *attrib_names;   /* nattribs names, e.g. "mfkit:table" (not "oiio:...") */
    const char *const *attrib_values;  /* nattribs NUL-terminated values */
} mf_image_write_options;

/*
 * mf_image_write with channel names, string attributes and exact half bits.  opt may be NULL
 * (32-bit floats, default names).  Atomic as mf_image_write; same status codes, MF_ERR_DOMAIN also
 * for NULL or empty channel names and NULL attribute names or values.
 */
mf_status mf_image_write_ex(const char *path, const mf_image *img, const mf_image_write_options *opt, char *msg,
                            size_t msg_size) MF_WARN_UNUSED;

/*
 * mf_image_write_ex into the temporary of an atomic write begun on the target path
 * (mf_io_atomic_begin; the format is that of a->path's extension), without the rename: for
 * several files committed together (mf_io_atomic_commit_all).  On failure a is aborted (its
 * temporary removed); on success commit or abort it.
 */
mf_status mf_image_write_into(mf_io_atomic *a, const mf_image *img, const mf_image_write_options *opt, char *msg,
                              size_t msg_size) MF_WARN_UNUSED;

/* Free the pixels of an image filled by mf_image_read and zero it.  NULL and zeroed images are
 * accepted (no-op); calling it twice is safe. */
void mf_image_free(mf_image *img);

#ifdef __cplusplus
}
#endif
#endif /* MF_IMAGE_H */
