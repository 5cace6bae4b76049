/*
 * mf_image_oiio.h -- the OpenImageIO 2.4 backend of the image API (target mfkit_image_oiio).
 *
 *     mf_image_set_backend(mf_image_oiio_backend());
 *
 * once at start-up, before the first image or EXR table call (mfkit/io/mf_image.h).  Every image
 * format OpenImageIO knows is read; written files carry only the attributes given (no time
 * stamp: OpenEXR files are bitwise the same between runs).
 */
#ifndef MF_IMAGE_OIIO_H
#define MF_IMAGE_OIIO_H

#include <mfkit/io/mf_image.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The backend (a static object; never NULL). */
const mf_image_backend *mf_image_oiio_backend(void);

#ifdef __cplusplus
}
#endif
#endif /* MF_IMAGE_OIIO_H */
