/*
 * mf_core.h -- constants, status codes, and small vector/matrix/frame helpers.
 *
 * Conventions (docs/conventions.md):
 *  - Shading frame is z-up: the geometric (macro) normal is (0, 0, 1).
 *  - Every direction points away from the surface: wo (view), wi (light), wm (micro-normal).
 *  - Angles are radians.  Degrees appear only at the CLI boundary with a `_deg` suffix.
 *  - Vectors and 3x3 matrices are small structs passed by value; matrices are row-major.
 *
 * Pure C11, libm only.  Nothing here allocates, prints or aborts.
 */
#ifndef MF_CORE_H
#define MF_CORE_H

#include <math.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Full-precision constants (M_PI is not ISO C). */
#define MF_PI        3.14159265358979323846264338327950288
#define MF_INV_PI    0.318309886183790671537767526745028724
#define MF_SQRT_PI   1.77245385090551602729816748334114518
#define MF_SQRT2     1.41421356237309504880168872420969808
#define MF_INV_SQRT_PI 0.564189583547756286948079451560772586

#if defined(__GNUC__) || defined(__clang__)
#define MF_WARN_UNUSED __attribute__((warn_unused_result))
#else
#define MF_WARN_UNUSED
#endif

/* Status codes of every function that allocates, reads or writes files, iterates or fits.
 * MF_OK is 0; mf_status_str() gives a fixed English text for each code. */
typedef enum mf_status {
    MF_OK = 0,
    MF_ERR_DOMAIN,       /* an argument is outside the documented domain (NaN, negative alpha, ...) */
    MF_ERR_ALLOC,        /* memory allocation failed */
    MF_ERR_IO,           /* a file could not be read or written */
    MF_ERR_FORMAT,       /* a file or stream is malformed or truncated */
    MF_ERR_NO_CONVERGENCE, /* an iterative method stopped before its tolerance */
    MF_ERR_UNSUPPORTED,  /* the feature was not built in (e.g. without Ceres or OpenImageIO) */
    MF_ERR_CHECK_FAILED, /* a validation check failed */
    MF_ERR_INTERNAL      /* a bug: an exception crossed a bridge, an invariant broke */
} mf_status;

/* Text for a status code; never NULL. */
const char *mf_status_str(mf_status s);

/* A value with an absolute error estimate (GSL's gsl_sf_result). */
typedef struct mf_result {
    double val;
    double err;
} mf_result;

typedef struct mf_vec3 {
    double x, y, z;
} mf_vec3;

/* Row-major 3x3 matrix: m[row][col]. */
typedef struct mf_mat3 {
    double m[3][3];
} mf_mat3;

/* An orthonormal frame: s, t, n are the images of x, y, z. */
typedef struct mf_frame {
    mf_vec3 s, t, n;
} mf_frame;

static inline mf_vec3 mf_vec3_make(double x, double y, double z) { mf_vec3 v = {x, y, z}; return v; }
static inline mf_vec3 mf_vec3_add(mf_vec3 a, mf_vec3 b) { return mf_vec3_make(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline mf_vec3 mf_vec3_sub(mf_vec3 a, mf_vec3 b) { return mf_vec3_make(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline mf_vec3 mf_vec3_scale(mf_vec3 a, double s) { return mf_vec3_make(a.x * s, a.y * s, a.z * s); }
static inline double mf_vec3_dot(mf_vec3 a, mf_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline mf_vec3 mf_vec3_cross(mf_vec3 a, mf_vec3 b)
{
    return mf_vec3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double mf_vec3_length(mf_vec3 a) { return sqrt(mf_vec3_dot(a, a)); }
/* Unit vector along a; the zero vector maps to NaNs (no silent default direction). */
static inline mf_vec3 mf_vec3_normalize(mf_vec3 a) { return mf_vec3_scale(a, 1.0 / mf_vec3_length(a)); }
static inline int mf_vec3_isfinite(mf_vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }

/* Mirror reflection of w about the unit normal n: 2 (w.n) n - w. */
static inline mf_vec3 mf_vec3_reflect(mf_vec3 w, mf_vec3 n)
{
    return mf_vec3_sub(mf_vec3_scale(n, 2.0 * mf_vec3_dot(w, n)), w);
}

/* Unit direction from spherical angles (theta from +z, phi from +x towards +y). */
static inline mf_vec3 mf_vec3_spherical(double theta, double phi)
{
    double st = sin(theta);
    return mf_vec3_make(st * cos(phi), st * sin(phi), cos(theta));
}

/* Matrix helpers. */
mf_mat3 mf_mat3_identity(void);
mf_mat3 mf_mat3_mul(mf_mat3 a, mf_mat3 b);
mf_vec3 mf_mat3_apply(mf_mat3 a, mf_vec3 v);
mf_mat3 mf_mat3_transpose(mf_mat3 a);
double mf_mat3_det(mf_mat3 a);
/* Inverse by the adjugate.  A singular or non-finite matrix gives MF_ERR_DOMAIN and leaves *out untouched. */
mf_status mf_mat3_inverse(mf_mat3 a, mf_mat3 *out) MF_WARN_UNUSED;

/* An orthonormal frame around the unit vector n, continuous everywhere except on a
 * set of measure zero, without branches on |n.z| thresholds [Duff et al. 2017, "Building an
 * Orthonormal Basis, Revisited", JCGT 6(1), Listing 3]. */
mf_frame mf_frame_from_normal(mf_vec3 n);
/* World -> local coordinates (dot with s, t, n) and back. */
mf_vec3 mf_frame_to_local(mf_frame f, mf_vec3 v);
mf_vec3 mf_frame_to_world(mf_frame f, mf_vec3 v);

/* Trigonometry of a unit direction in the shading frame, without calling trig functions. */
static inline double mf_cos_theta(mf_vec3 w) { return w.z; }
static inline double mf_sin_theta_sq(mf_vec3 w) { double s = w.x * w.x + w.y * w.y; return s; }

#ifdef __cplusplus
}
#endif
#endif /* MF_CORE_H */
