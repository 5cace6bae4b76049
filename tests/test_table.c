/* test_table.c -- the table type: axes, texel centres, records, interpolation (mf_table.h). */
#include "mf_test.h"
#include "mfkit/mf_table.h"
#include "mfkit/mf_rng.h"

#include <float.h>
#include <string.h>

static mf_table_axis axis(const char *name, const char *phys, int size, double lo, double hi, mf_axis_mapping m,
                          double pmin)
{
    mf_table_axis a;
    memset(&a, 0, sizeof a);
    snprintf(a.name, sizeof a.name, "%s", name);
    snprintf(a.physical, sizeof a.physical, "%s", phys);
    a.size = size;
    a.lo = lo;
    a.hi = hi;
    a.mapping = m;
    a.physical_min = pmin;
    return a;
}

int main(void)
{
    /* The LTC layout: axis 0 roughness r (alpha = max(r^2, 1e-4)), axis 1 u = sqrt(1 - cos theta). */
    mf_table_axis axes[2] = {axis("r", "alpha", 64, 0.0, 1.0, MF_AXIS_SQUARE, 1e-4),
                             axis("u", "cos_theta_o", 32, 0.0, 1.0, MF_AXIS_ONE_MINUS_SQUARE, -INFINITY)};
    const char *fields[3] = {"a", "b", "c"};
    mf_table t;
    CHECK(mf_table_create(&t, 2, axes, 3, fields) == MF_OK);
    CHECK(mf_table_texels(&t) == 64 * 32);
    /* record layout: first axis fastest */
    int idx[2] = {5, 7};
    CHECK(mf_table_record(&t, idx) == t.data + (5 + 64 * 7) * 3);
    int bad_idx[2] = {64, 0};
    CHECK(mf_table_record(&t, bad_idx) == NULL);
    CHECK(mf_table_field(&t, "c") == 2 && mf_table_field(&t, "d") == -1);

    /* texel centres and physical values */
    CHECK(mf_table_axis_param(&t.axes[0], 0) == 0.0);
    CHECK(mf_table_axis_param(&t.axes[0], 63) == 1.0);
    CHECK_REL(mf_table_axis_param(&t.axes[0], 21), 21.0 / 63.0, DBL_EPSILON);
    CHECK(mf_table_axis_physical(&t.axes[0], 0.0) == 1e-4); /* clamped */
    CHECK_REL(mf_table_axis_physical(&t.axes[0], 0.5), 0.25, DBL_EPSILON);
    CHECK_REL(mf_table_axis_physical(&t.axes[1], 0.5), 0.75, DBL_EPSILON);
    /* texture coordinates: centre of texel i at (i + 0.5) / n; first and last centre */
    CHECK_REL(mf_table_uv_from_param(&t.axes[0], 0.0), 0.5 / 64.0, DBL_EPSILON);
    CHECK_REL(mf_table_uv_from_param(&t.axes[0], 1.0), 63.5 / 64.0, DBL_EPSILON);
    CHECK_REL(mf_table_param_from_uv(&t.axes[1], mf_table_uv_from_param(&t.axes[1], 0.3)), 0.3, 4 * DBL_EPSILON);
    char desc[128];
    mf_axis_describe(&t.axes[0], desc, sizeof desc);
    CHECK(strcmp(desc, "alpha = r^2, clamped to >= 0.0001") == 0);

    /* fill with a bilinear function plus noise, and NaN in one far texel */
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(11), 0);
    for (int j = 0; j < 32; ++j)
        for (int i = 0; i < 64; ++i) {
            int k[2] = {i, j};
            double *r = mf_table_record(&t, k);
            r[0] = mf_pcg32_next_double(&rng) - 0.5;
            r[1] = 2.0 * mf_table_axis_param(&t.axes[0], i) - 3.0 * mf_table_axis_param(&t.axes[1], j) + 0.25;
            r[2] = (i == 63 && j == 31) ? NAN : -0.0;
        }
    /* exact at texel centres, bit for bit (including -0), even next to a NaN */
    int exact = 1;
    for (int j = 0; j < 32; ++j)
        for (int i = 0; i < 64; ++i) {
            int k[2] = {i, j};
            double p[2] = {mf_table_axis_param(&t.axes[0], i), mf_table_axis_param(&t.axes[1], j)}, out[3];
            CHECK(mf_table_lookup(&t, p, out) == MF_OK);
            const double *r = mf_table_record(&t, k);
            if (i == 63 && j == 31)
                exact &= (memcmp(out, r, 2 * sizeof(double)) == 0) && isnan(out[2]);
            else
                exact &= (memcmp(out, r, sizeof out) == 0);
        }
    CHECK(exact);
    /* multilinear interpolation reproduces a bilinear function to rounding (16 eps of its scale 3) */
    for (int k = 0; k < 1000; ++k) {
        double p[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng) * 0.9}, out[3];
        CHECK(mf_table_lookup(&t, p, out) == MF_OK);
        CHECK_ABS(out[1], 2.0 * p[0] - 3.0 * p[1] + 0.25, 16 * 3 * DBL_EPSILON);
    }
    /* clamp to edge, NaN refused */
    double outside[2] = {-5.0, 7.0}, corner[2] = {0.0, 1.0}, o1[3], o2[3];
    CHECK(mf_table_lookup(&t, outside, o1) == MF_OK);
    CHECK(mf_table_lookup(&t, corner, o2) == MF_OK);
    CHECK(o1[1] == o2[1]);
    double nanp[2] = {NAN, 0.5};
    CHECK(mf_table_lookup(&t, nanp, o1) == MF_ERR_DOMAIN);
    double mn, mx;
    size_t nans;
    mf_table_field_range(&t, 2, &mn, &mx, &nans);
    CHECK(nans == 1 && mn == 0.0 && mx == 0.0);

    /* metadata */
    CHECK(mf_table_set_meta(&t, "brdf", "ggx") == MF_OK);
    CHECK(mf_table_set_meta(&t, "brdf", "beckmann") == MF_OK);
    CHECK(strcmp(mf_table_get_meta(&t, "brdf"), "beckmann") == 0);
    CHECK(mf_table_get_meta(&t, "nope") == NULL);
    CHECK(mf_table_set_meta(&t, "bad key", "x") == MF_ERR_DOMAIN);
    mf_table c;
    CHECK(mf_table_copy(&c, &t) == MF_OK);
    CHECK(c.data != t.data && memcmp(c.data, t.data, 64 * 32 * 2 * sizeof(double)) == 0);
    mf_table_free(&c);
    mf_table_free(&t);
    CHECK(t.data == NULL);

    /* invalid definitions are refused with a zeroed table */
    mf_table_axis dup[2] = {axes[0], axes[0]};
    CHECK(mf_table_create(&t, 2, dup, 3, fields) == MF_ERR_DOMAIN && t.data == NULL);
    const char *dupf[2] = {"a", "a"};
    CHECK(mf_table_create(&t, 1, axes, 2, dupf) == MF_ERR_DOMAIN);
    const char *badf[1] = {"a-b"};
    CHECK(mf_table_create(&t, 1, axes, 1, badf) == MF_ERR_DOMAIN);
    mf_table_axis flat = axis("x", "x", 4, 1.0, 1.0, MF_AXIS_IDENTITY, -INFINITY);
    CHECK(mf_table_create(&t, 1, &flat, 1, fields) == MF_ERR_DOMAIN);
    mf_table_axis nan_axis = axis("x", "x", 4, 0.0, NAN, MF_AXIS_IDENTITY, -INFINITY);
    CHECK(mf_table_create(&t, 1, &nan_axis, 1, fields) == MF_ERR_DOMAIN);
    CHECK(mf_table_create(&t, 0, axes, 1, fields) == MF_ERR_DOMAIN);
    /* a one-texel axis is allowed (constant along it) */
    mf_table_axis one = axis("x", "x", 1, 0.5, 0.5, MF_AXIS_IDENTITY, -INFINITY);
    CHECK(mf_table_create(&t, 1, &one, 1, fields) == MF_OK);
    t.data[0] = 3.0;
    double q = 0.9, qo;
    CHECK(mf_table_lookup(&t, &q, &qo) == MF_OK && qo == 3.0);
    mf_table_free(&t);
    mf_axis_mapping m;
    CHECK(mf_axis_mapping_parse("one_minus_square", &m) == 0 && m == MF_AXIS_ONE_MINUS_SQUARE);
    CHECK(mf_axis_mapping_parse("bogus", &m) != 0);
    MF_TEST_MAIN_END();
}
