/* mf_image.c -- the image API's dispatcher (mf_image.h): argument checks, the atomic write and
 * the "no backend" answer; the pixels are the backend's business. */
#include "mfkit/io/mf_image.h"

#include <ctype.h>
#include <stdlib.h>
#include <string.h>

#include "mfkit/io/mf_io.h"

#if defined(__STDC_NO_ATOMICS__)
static const mf_image_backend *g_backend;
#define LOAD_BACKEND() g_backend
#define STORE_BACKEND(b) (g_backend = (b))
#else
#include <stdatomic.h>
static _Atomic(const mf_image_backend *) g_backend;
#define LOAD_BACKEND() atomic_load(&g_backend)
#define STORE_BACKEND(b) atomic_store(&g_backend, (b))
#endif

void mf_image_set_backend(const mf_image_backend *backend) { STORE_BACKEND(backend); }

const mf_image_backend *mf_image_get_backend(void) { return LOAD_BACKEND(); }

/* "path: reading EXR needs the OpenImageIO build" (the extension in capitals). */
static mf_status no_backend(const char *path, const char *verb, char *msg, size_t msg_size)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(slash ? slash + 1 : path, '.');
    char ext[16] = "images";
    if (dot && dot[1] && strlen(dot + 1) < sizeof ext) {
        size_t i = 0;
        for (const char *c = dot + 1; *c; ++c)
            ext[i++] = (char)toupper((unsigned char)*c);
        ext[i] = '\0';
    }
    mf_io_msg(msg, msg_size, path, "%s %s needs the OpenImageIO build (this program has no image backend)", verb, ext);
    return MF_ERR_UNSUPPORTED;
}

void mf_image_free(mf_image *img)
{
    if (!img)
        return;
    free(img->pixels);
    img->pixels = NULL;
    img->width = img->height = img->channels = 0;
}

void mf_image_info_free(mf_image_info *info)
{
    if (!info)
        return;
    if (info->channel_names)
        for (int c = 0; c < info->nchannels; ++c)
            free(info->channel_names[c]);
    free(info->channel_names);
    free(info->attrib_value);
    memset(info, 0, sizeof *info);
}

mf_status mf_image_read(const char *path, mf_image *out, char *msg, size_t msg_size)
{
    return mf_image_read_ex(path, out, NULL, NULL, msg, msg_size);
}

mf_status mf_image_read_ex(const char *path, mf_image *out, const char *attrib_name, mf_image_info *info, char *msg,
                           size_t msg_size)
{
    mf_io_msg_clear(msg, msg_size);
    if (info)
        memset(info, 0, sizeof *info);
    if (out)
        memset(out, 0, sizeof *out);
    if (!path || !out) {
        mf_io_msg(msg, msg_size, path, "invalid argument (NULL path or image)");
        return MF_ERR_DOMAIN;
    }
    const mf_image_backend *b = LOAD_BACKEND();
    if (!b || !b->read)
        return no_backend(path, "reading", msg, msg_size);
    mf_status st = b->read(path, out, attrib_name, info, msg, msg_size);
    if (st != MF_OK) {
        mf_image_free(out);
        mf_image_info_free(info);
    }
    return st;
}

mf_status mf_image_write(const char *path, const mf_image *img, int half_float, char *msg, size_t msg_size)
{
    mf_image_write_options opt;
    memset(&opt, 0, sizeof opt);
    opt.half_float = half_float;
    return mf_image_write_ex(path, img, &opt, msg, msg_size);
}

/* Argument checks of a write; the options copied into *opt (zeroed if options is NULL). */
static mf_status write_args(const char *path, const mf_image *img, const mf_image_write_options *options,
                            mf_image_write_options *opt, char *msg, size_t msg_size)
{
    memset(opt, 0, sizeof *opt);
    if (options)
        *opt = *options;
    const int use_half_bits = opt->half_float && opt->half_bits != NULL;
    if (!path || !*path || !img || (!img->pixels && !use_half_bits) || img->width < 1 || img->height < 1 ||
        img->channels < 1 || (size_t)img->width > SIZE_MAX / sizeof(float) / (size_t)img->height / (size_t)img->channels) {
        mf_io_msg(msg, msg_size, path, "invalid argument (NULL or empty path, NULL image or pixels, or size < 1)");
        return MF_ERR_DOMAIN;
    }
    if (opt->channel_names)
        for (int c = 0; c < img->channels; ++c)
            if (!opt->channel_names[c] || !opt->channel_names[c][0]) {
                mf_io_msg(msg, msg_size, path, "invalid argument (NULL or empty channel name)");
                return MF_ERR_DOMAIN;
            }
    if (opt->nattribs < 0 || (opt->nattribs > 0 && (!opt->attrib_names || !opt->attrib_values))) {
        mf_io_msg(msg, msg_size, path, "invalid argument (attribute arrays)");
        return MF_ERR_DOMAIN;
    }
    for (int a = 0; a < opt->nattribs; ++a)
        if (!opt->attrib_names[a] || !opt->attrib_names[a][0] || !opt->attrib_values[a]) {
            mf_io_msg(msg, msg_size, path, "invalid argument (NULL or empty attribute name, or NULL value)");
            return MF_ERR_DOMAIN;
        }
    const mf_image_backend *b = LOAD_BACKEND();
    if (!b || !b->write)
        return no_backend(path, "writing", msg, msg_size);
    return MF_OK;
}

mf_status mf_image_write_into(mf_io_atomic *a, const mf_image *img, const mf_image_write_options *options, char *msg,
                              size_t msg_size)
{
    mf_io_msg_clear(msg, msg_size);
    if (!a || !a->tmp_path || a->finished) {
        mf_io_msg(msg, msg_size, a ? a->path : NULL, "invalid argument (no open temporary file)");
        mf_io_atomic_abort(a);
        return MF_ERR_DOMAIN;
    }
    mf_image_write_options opt;
    mf_status st = write_args(a->path, img, options, &opt, msg, msg_size);
    if (st != MF_OK) {
        mf_io_atomic_abort(a);
        return st;
    }
    /* the backend writes the temporary by name */
    if (a->file) {
        int closed = fclose(a->file);
        a->file = NULL;
        if (closed != 0) {
            mf_io_msg(msg, msg_size, a->path, "cannot close temporary file %s", a->tmp_path);
            mf_io_atomic_abort(a);
            return MF_ERR_IO;
        }
    }
    st = LOAD_BACKEND()->write(a->path, a->tmp_path, img, &opt, msg, msg_size);
    if (st != MF_OK)
        mf_io_atomic_abort(a);
    return st;
}

mf_status mf_image_write_ex(const char *path, const mf_image *img, const mf_image_write_options *options, char *msg,
                            size_t msg_size)
{
    mf_io_msg_clear(msg, msg_size);
    mf_image_write_options opt;
    mf_status st = write_args(path, img, options, &opt, msg, msg_size);
    if (st != MF_OK)
        return st;
    mf_io_atomic a;
    if ((st = mf_io_atomic_begin(&a, path, msg, msg_size)) != MF_OK)
        return st;
    if ((st = mf_image_write_into(&a, img, &opt, msg, msg_size)) != MF_OK)
        return st;
    return mf_io_atomic_commit(&a, msg, msg_size);
}
