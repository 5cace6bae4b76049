// mf_image_oiio.cpp -- the OpenImageIO 2.4 backend of the image API (mfkit/io/mf_image.h).
//
// No exception crosses the C boundary; every error becomes a status and a "path: reason" message.
// The dispatcher checks the arguments and owns the atomic write (temporary file, fsync, rename).

#include "mfkit/fit/mf_image_oiio.h"

#include <OpenImageIO/imageio.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <string>

#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>
#define MF_HAVE_GETPID 1
#endif

namespace {

// "path: prefix reason" into msg, on one line, truncated to fit.  Never allocates or throws, so
// it is safe in the catch handlers.
void set_msg(char *msg, size_t msg_size, const char *path, const char *prefix, const char *reason) noexcept
{
    if (msg == nullptr || msg_size == 0)
        return;
    if (reason == nullptr || reason[0] == '\0')
        reason = "unknown error";
    std::snprintf(msg, msg_size, "%s: %s%s", path ? path : "(null)", prefix, reason);
    // OIIO joins several errors with newlines: keep one line, without trailing blanks.
    size_t len = std::strlen(msg);
    while (len > 0 && (msg[len - 1] == '\n' || msg[len - 1] == '\r' || msg[len - 1] == ' '))
        msg[--len] = '\0';
    for (char *c = msg; *c != '\0'; ++c)
        if (*c == '\n' || *c == '\r')
            *c = ';';
}

void set_msg(char *msg, size_t msg_size, const char *path, const std::string &reason)
{
    set_msg(msg, msg_size, path, "", reason.c_str());
}

// OIIO keeps a per-thread error for failed open/create calls; fetch and clear it.
std::string global_error()
{
    std::string e = OIIO::geterror();
    return e.empty() ? std::string("unknown OpenImageIO error") : e;
}

// The error of an ImageInput/ImageOutput (cleared on retrieval, so OIIO never complains
// about an unretrieved error), or the global one if the object has none.
template <typename T> std::string object_error(const T &obj)
{
    std::string e = obj.geterror();
    if (e.empty())
        e = OIIO::geterror();
    return e.empty() ? std::string("unknown OpenImageIO error") : e;
}

bool file_is_readable(const char *path)
{
    std::FILE *f = std::fopen(path, "rb");
    if (f == nullptr)
        return false;
    std::fclose(f);
    return true;
}

// pixels count = w * h * c as size_t, or false if it overflows (or the byte count does).
bool pixel_count(long long w, long long h, long long c, size_t *n)
{
    if (w <= 0 || h <= 0 || c <= 0)
        return false;
    const unsigned long long max = std::numeric_limits<size_t>::max() / sizeof(float);
    const unsigned long long uw = static_cast<unsigned long long>(w), uh = static_cast<unsigned long long>(h),
                             uc = static_cast<unsigned long long>(c);
    if (uw > max / uh || uw * uh > max / uc)
        return false;
    *n = static_cast<size_t>(uw * uh * uc);
    return true;
}

} // namespace

namespace {

void free_info(mf_image_info *info)
{
    if (info->channel_names != nullptr)
        for (int c = 0; c < info->nchannels; ++c)
            std::free(info->channel_names[c]);
    std::free(info->channel_names);
    std::free(info->attrib_value);
    std::memset(info, 0, sizeof *info);
}

char *dup_cstr(const std::string &s)
{
    char *p = static_cast<char *>(std::malloc(s.size() + 1));
    if (p != nullptr)
        std::memcpy(p, s.c_str(), s.size() + 1);
    return p;
}

// Fills info from spec; false on allocation failure (info then zeroed).
bool fill_info(const OIIO::ImageSpec &spec, const char *attrib_name, mf_image_info *info)
{
    std::memset(info, 0, sizeof *info);
    info->channel_names = static_cast<char **>(std::calloc(static_cast<size_t>(spec.nchannels), sizeof(char *)));
    if (info->channel_names == nullptr)
        return false;
    info->nchannels = spec.nchannels;
    for (int c = 0; c < spec.nchannels; ++c) {
        const std::string name = (c < static_cast<int>(spec.channelnames.size())) ? spec.channelnames[c] : std::string();
        info->channel_names[c] = dup_cstr(name);
        if (info->channel_names[c] == nullptr) {
            free_info(info);
            return false;
        }
    }
    if (attrib_name != nullptr) {
        const OIIO::ParamValue *p = spec.find_attribute(attrib_name, OIIO::TypeDesc::STRING, true);
        if (p != nullptr && p->nvalues() == 1) {
            info->attrib_value = dup_cstr(p->get_ustring_indexed(0).string());
            if (info->attrib_value == nullptr) {
                free_info(info);
                return false;
            }
        }
    }
    std::snprintf(info->pixel_type, sizeof info->pixel_type, "%s", spec.format.c_str());
    return true;
}

mf_status oiio_read(const char *path, mf_image *out, const char *attrib_name, mf_image_info *info, char *msg,
                    size_t msg_size)
{
    float *pixels = nullptr;
    try {
        // Return alpha as stored: no premultiplication on read (PNG, TIFF, ...).
        OIIO::ImageSpec config;
        config.attribute("oiio:UnassociatedAlpha", 1);
        auto in = OIIO::ImageInput::open(path, &config);
        if (!in) {
            const std::string e = global_error();
            // OIIO reports "cannot open" and "cannot parse" alike; tell them apart ourselves.
            if (!file_is_readable(path)) {
                const int err = errno;
                set_msg(msg, msg_size, path, e + " (" + std::strerror(err) + ")");
                return MF_ERR_IO;
            }
            set_msg(msg, msg_size, path, e);
            return MF_ERR_FORMAT;
        }
        const OIIO::ImageSpec spec = in->spec();
        if (spec.deep || spec.depth > 1) {
            in->close();
            set_msg(msg, msg_size, path, spec.deep ? "deep images are not supported" : "volume images are not supported");
            return MF_ERR_UNSUPPORTED;
        }
        size_t n = 0;
        if (!pixel_count(spec.width, spec.height, spec.nchannels, &n)) {
            in->close();
            set_msg(msg, msg_size, path,
                    "invalid image size " + std::to_string(spec.width) + " x " + std::to_string(spec.height) + " x " +
                        std::to_string(spec.nchannels));
            return MF_ERR_FORMAT;
        }
        pixels = static_cast<float *>(std::malloc(n * sizeof(float)));
        if (pixels == nullptr) {
            in->close();
            set_msg(msg, msg_size, path, "out of memory for " + std::to_string(n) + " floats");
            return MF_ERR_ALLOC;
        }
        if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels)) {
            const std::string e = object_error(*in);
            in->close();
            std::free(pixels);
            set_msg(msg, msg_size, path, e);
            return MF_ERR_FORMAT;
        }
        if (!in->close()) {
            const std::string e = object_error(*in);
            std::free(pixels);
            set_msg(msg, msg_size, path, e);
            return MF_ERR_FORMAT;
        }
        (void)in->geterror(); // nothing pending when the input is destroyed
        if (info != nullptr && !fill_info(spec, attrib_name, info)) {
            std::free(pixels);
            set_msg(msg, msg_size, path, "", "out of memory");
            return MF_ERR_ALLOC;
        }
        out->width = spec.width;
        out->height = spec.height;
        out->channels = spec.nchannels;
        out->pixels = pixels;
        return MF_OK;
    } catch (const std::bad_alloc &) {
        std::free(pixels);
        if (info != nullptr)
            free_info(info);
        set_msg(msg, msg_size, path, "", "out of memory");
        return MF_ERR_ALLOC;
    } catch (const std::exception &ex) {
        std::free(pixels);
        if (info != nullptr)
            free_info(info);
        set_msg(msg, msg_size, path, "internal error: ", ex.what());
        return MF_ERR_INTERNAL;
    } catch (...) {
        std::free(pixels);
        if (info != nullptr)
            free_info(info);
        set_msg(msg, msg_size, path, "internal error: ", "unknown exception");
        return MF_ERR_INTERNAL;
    }
}

mf_status oiio_write(const char *path, const char *tmp_path, const mf_image *img, const mf_image_write_options *options,
                     char *msg, size_t msg_size)
{
    mf_image_write_options opt;
    std::memset(&opt, 0, sizeof opt);
    if (options != nullptr)
        opt = *options;
    const bool use_half_bits = opt.half_float && opt.half_bits != nullptr;
    try {
        // The writer is chosen by the extension of path; the dispatcher's temporary has none.
        auto out = OIIO::ImageOutput::create(path);
        if (!out) {
            set_msg(msg, msg_size, path, global_error());
            return MF_ERR_UNSUPPORTED;
        }
        OIIO::ImageSpec spec(img->width, img->height, img->channels,
                             opt.half_float ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
        // The pixels are written as given (no un-premultiplication by alpha in PNG, TIFF, ...).
        spec.attribute("oiio:UnassociatedAlpha", 1);
        if (opt.channel_names != nullptr) {
            for (int c = 0; c < img->channels; ++c)
                spec.channelnames[static_cast<size_t>(c)] = opt.channel_names[c];
            spec.alpha_channel = -1; // named records, not colour: no channel is alpha
            spec.z_channel = -1;
        }
        for (int a = 0; a < opt.nattribs; ++a)
            spec.attribute(opt.attrib_names[a], opt.attrib_values[a]);
        // OpenImageIO stamps new files with the current time (OpenEXR "capDate") unless the spec
        // has a "DateTime": an empty one is written as nothing, so the output is bitwise the same
        // between runs (checked by tests/test_image.c).
        if (spec.find_attribute("DateTime") == nullptr)
            spec.attribute("DateTime", "");
        if (!out->open(tmp_path, spec)) {
            // The temporary file could be created, so this is (nearly always) the format refusing
            // the image, e.g. more channels than it stores.
            const std::string e = object_error(*out);
            set_msg(msg, msg_size, path, e);
            return MF_ERR_UNSUPPORTED;
        }
        const bool ok = use_half_bits ? out->write_image(OIIO::TypeDesc::HALF, opt.half_bits)
                                      : out->write_image(OIIO::TypeDesc::FLOAT, img->pixels);
        if (!ok) {
            const std::string e = object_error(*out);
            out->close();
            (void)out->geterror();
            set_msg(msg, msg_size, path, e);
            return MF_ERR_IO;
        }
        if (!out->close()) {
            const std::string e = object_error(*out);
            set_msg(msg, msg_size, path, e);
            return MF_ERR_IO;
        }
        (void)out->geterror();
        out.reset();
        return MF_OK;
    } catch (const std::bad_alloc &) {
        set_msg(msg, msg_size, path, "", "out of memory");
        return MF_ERR_ALLOC;
    } catch (const std::exception &ex) {
        set_msg(msg, msg_size, path, "internal error: ", ex.what());
        return MF_ERR_INTERNAL;
    } catch (...) {
        set_msg(msg, msg_size, path, "internal error: ", "unknown exception");
        return MF_ERR_INTERNAL;
    }
}

} // namespace

extern "C" const mf_image_backend *mf_image_oiio_backend(void)
{
    static const mf_image_backend backend = {"OpenImageIO " OIIO_VERSION_STRING, oiio_read, oiio_write};
    return &backend;
}
