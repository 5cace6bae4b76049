/* test_core.c -- vectors, matrices, frames, status texts (mf_core.h). */
#include "mf_test.h"
#include "mfkit/mf_core.h"
#include "mfkit/mf_rng.h"

#include <float.h>
#include <string.h>

int main(void)
{
    /* status texts exist and differ */
    for (int s = MF_OK; s <= MF_ERR_INTERNAL; ++s) {
        CHECK(mf_status_str((mf_status)s) != NULL);
        CHECK(strcmp(mf_status_str((mf_status)s), "unknown status") != 0);
    }
    CHECK(strcmp(mf_status_str((mf_status)999), "unknown status") == 0);

    /* inverse: A A^-1 = I to 16 eps for a well-conditioned matrix (cond ~ 10) */
    mf_mat3 a = {{{2.0, 0.3, -0.1}, {0.5, 1.5, 0.2}, {-0.4, 0.1, 3.0}}}, inv;
    CHECK(mf_mat3_inverse(a, &inv) == MF_OK);
    mf_mat3 p = mf_mat3_mul(a, inv);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            CHECK_ABS(p.m[i][j], i == j ? 1.0 : 0.0, 16 * DBL_EPSILON);
    CHECK_REL(mf_mat3_det(a) * mf_mat3_det(inv), 1.0, 16 * DBL_EPSILON);
    /* singular and NaN matrices are refused and leave the output untouched */
    mf_mat3 sing = {{{1, 2, 3}, {2, 4, 6}, {0, 0, 1}}}, keep = mf_mat3_identity();
    CHECK(mf_mat3_inverse(sing, &keep) == MF_ERR_DOMAIN);
    CHECK(keep.m[0][0] == 1.0 && keep.m[0][1] == 0.0);
    mf_mat3 bad = a;
    bad.m[1][1] = NAN;
    CHECK(mf_mat3_inverse(bad, &keep) == MF_ERR_DOMAIN);
    mf_vec3 v = mf_mat3_apply(mf_mat3_transpose(a), mf_vec3_make(1, 0, 0));
    CHECK(v.x == 2.0 && v.y == 0.3 && v.z == -0.1);

    /* frames: orthonormal and right-handed for normals everywhere, including the poles and
     * z = 0 (the branch-free construction of Duff et al. must not break there). 8 eps: a few
     * roundings per component. */
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(7), 1);
    mf_vec3 normals[1006];
    int n = 0;
    normals[n++] = mf_vec3_make(0, 0, 1);
    normals[n++] = mf_vec3_make(0, 0, -1);
    normals[n++] = mf_vec3_make(1, 0, 0);
    normals[n++] = mf_vec3_make(0, -1, 0);
    normals[n++] = mf_vec3_normalize(mf_vec3_make(1e-300, 1e-300, -1));
    normals[n++] = mf_vec3_normalize(mf_vec3_make(1, 1, 0));
    while (n < 1006) {
        double u[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)};
        double z = 1 - 2 * u[0], r = sqrt(1 - z * z);
        normals[n++] = mf_vec3_make(r * cos(2 * MF_PI * u[1]), r * sin(2 * MF_PI * u[1]), z);
    }
    for (int i = 0; i < n; ++i) {
        mf_frame f = mf_frame_from_normal(normals[i]);
        CHECK_ABS(mf_vec3_dot(f.s, f.s), 1.0, 8 * DBL_EPSILON);
        CHECK_ABS(mf_vec3_dot(f.t, f.t), 1.0, 8 * DBL_EPSILON);
        CHECK_ABS(mf_vec3_dot(f.s, f.t), 0.0, 8 * DBL_EPSILON);
        CHECK_ABS(mf_vec3_dot(f.s, f.n), 0.0, 8 * DBL_EPSILON);
        CHECK_ABS(mf_vec3_dot(mf_vec3_cross(f.s, f.t), f.n), 1.0, 8 * DBL_EPSILON);
        mf_vec3 w = mf_vec3_normalize(mf_vec3_make(0.3, -0.2, 0.9));
        mf_vec3 back = mf_frame_to_world(f, mf_frame_to_local(f, w));
        CHECK_ABS(back.x, w.x, 8 * DBL_EPSILON);
        CHECK_ABS(back.y, w.y, 8 * DBL_EPSILON);
        CHECK_ABS(back.z, w.z, 8 * DBL_EPSILON);
    }
    /* reflection about z mirrors x and y */
    mf_vec3 r = mf_vec3_reflect(mf_vec3_make(0.6, 0.0, 0.8), mf_vec3_make(0, 0, 1));
    CHECK_ABS(r.x, -0.6, DBL_EPSILON);
    CHECK_ABS(r.z, 0.8, DBL_EPSILON);
    /* spherical: theta from +z, phi from +x towards +y */
    mf_vec3 s = mf_vec3_spherical(0.5 * MF_PI, 0.5 * MF_PI);
    CHECK_ABS(s.y, 1.0, DBL_EPSILON);
    CHECK_ABS(s.z, 0.0, DBL_EPSILON);
    MF_TEST_MAIN_END();
}
