/* mf_core.c -- status texts and matrix/frame helpers (see mf_core.h). */
#include "mfkit/mf_core.h"

const char *mf_status_str(mf_status s)
{
    switch (s) {
    case MF_OK: return "success";
    case MF_ERR_DOMAIN: return "argument outside the domain";
    case MF_ERR_ALLOC: return "out of memory";
    case MF_ERR_IO: return "input/output error";
    case MF_ERR_FORMAT: return "malformed or truncated data";
    case MF_ERR_NO_CONVERGENCE: return "iteration did not converge";
    case MF_ERR_UNSUPPORTED: return "feature not built in";
    case MF_ERR_CHECK_FAILED: return "validation check failed";
    case MF_ERR_INTERNAL: return "internal error";
    }
    return "unknown status";
}

mf_mat3 mf_mat3_identity(void)
{
    mf_mat3 r = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    return r;
}

mf_mat3 mf_mat3_mul(mf_mat3 a, mf_mat3 b)
{
    mf_mat3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
    return r;
}

mf_vec3 mf_mat3_apply(mf_mat3 a, mf_vec3 v)
{
    return mf_vec3_make(a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z,
                        a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
                        a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z);
}

mf_mat3 mf_mat3_transpose(mf_mat3 a)
{
    mf_mat3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r.m[i][j] = a.m[j][i];
    return r;
}

double mf_mat3_det(mf_mat3 a)
{
    return a.m[0][0] * (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1])
         - a.m[0][1] * (a.m[1][0] * a.m[2][2] - a.m[1][2] * a.m[2][0])
         + a.m[0][2] * (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]);
}

mf_status mf_mat3_inverse(mf_mat3 a, mf_mat3 *out)
{
    double det = mf_mat3_det(a);
    if (!isfinite(det) || det == 0.0)
        return MF_ERR_DOMAIN;
    mf_mat3 r;
    r.m[0][0] = (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) / det;
    r.m[0][1] = (a.m[0][2] * a.m[2][1] - a.m[0][1] * a.m[2][2]) / det;
    r.m[0][2] = (a.m[0][1] * a.m[1][2] - a.m[0][2] * a.m[1][1]) / det;
    r.m[1][0] = (a.m[1][2] * a.m[2][0] - a.m[1][0] * a.m[2][2]) / det;
    r.m[1][1] = (a.m[0][0] * a.m[2][2] - a.m[0][2] * a.m[2][0]) / det;
    r.m[1][2] = (a.m[0][2] * a.m[1][0] - a.m[0][0] * a.m[1][2]) / det;
    r.m[2][0] = (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]) / det;
    r.m[2][1] = (a.m[0][1] * a.m[2][0] - a.m[0][0] * a.m[2][1]) / det;
    r.m[2][2] = (a.m[0][0] * a.m[1][1] - a.m[0][1] * a.m[1][0]) / det;
    *out = r;
    return MF_OK;
}

mf_frame mf_frame_from_normal(mf_vec3 n)
{
    /* [Duff et al. 2017, Listing 3]: sign = copysign(1, n.z) keeps the frame defined at n.z = 0. */
    double sign = copysign(1.0, n.z);
    double a = -1.0 / (sign + n.z);
    double b = n.x * n.y * a;
    mf_frame f;
    f.s = mf_vec3_make(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    f.t = mf_vec3_make(b, sign + n.y * n.y * a, -n.y);
    f.n = n;
    return f;
}

mf_vec3 mf_frame_to_local(mf_frame f, mf_vec3 v)
{
    return mf_vec3_make(mf_vec3_dot(v, f.s), mf_vec3_dot(v, f.t), mf_vec3_dot(v, f.n));
}

mf_vec3 mf_frame_to_world(mf_frame f, mf_vec3 v)
{
    return mf_vec3_add(mf_vec3_add(mf_vec3_scale(f.s, v.x), mf_vec3_scale(f.t, v.y)), mf_vec3_scale(f.n, v.z));
}
