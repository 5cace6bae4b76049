/* test_table.c -- the table type: axes, texel centres, records, interpolation (mf_table.h). */
#include "mf_test.h"
#include "mfkit/mf_table.h"
#include "mfkit/mf_rng.h"

#include <float.h>
#include <stdlib.h>
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

/* A table of naxes axes (sizes[k], ranges [lo_k, hi_k] with a reversed axis among them) whose
 * 2 fields hold a multilinear function of the parameters (field 0) and random values in [-1, 1]
 * (field 1). */
static const double k_mcoef[MF_TABLE_MAX_AXES] = {0.7, -1.3, 0.4, 2.1, -0.6, 1.1};

static double multilinear(const double *p, int naxes)
{
    double v = 0.25, prod = 1.0;
    for (int k = 0; k < naxes; ++k) {
        v += k_mcoef[k] * p[k];
        prod *= p[k];
    }
    return v + 0.5 * prod; /* the product term: linear in each p_k separately */
}

static int nd_table(mf_table *t, int naxes, const int *sizes, mf_pcg32 *rng)
{
    mf_table_axis ax[MF_TABLE_MAX_AXES];
    static const char *const names[MF_TABLE_MAX_AXES] = {"a0", "a1", "a2", "a3", "a4", "a5"};
    for (int k = 0; k < naxes; ++k)
        ax[k] = axis(names[k], names[k], sizes[k], k == 3 ? 1.0 : -0.5 + 0.1 * k, k == 3 ? -2.0 : 1.5 + 0.2 * k,
                     MF_AXIS_IDENTITY, -INFINITY);
    const char *fields[2] = {"lin", "rnd"};
    if (mf_table_create(t, naxes, ax, 2, fields) != MF_OK)
        return 0;
    int idx[MF_TABLE_MAX_AXES];
    for (size_t i = 0; i < mf_table_texels(t); ++i) {
        size_t r = i;
        double p[MF_TABLE_MAX_AXES];
        for (int k = 0; k < naxes; ++k) {
            idx[k] = (int)(r % (size_t)sizes[k]);
            r /= (size_t)sizes[k];
            p[k] = mf_table_axis_param(&t->axes[k], idx[k]);
        }
        double *rec = mf_table_record(t, idx);
        if (rec != t->data + i * 2) /* the record layout: first axis fastest */
            return 0;
        rec[0] = multilinear(p, naxes);
        rec[1] = 2.0 * mf_pcg32_next_double(rng) - 1.0;
    }
    return 1;
}

/* A random point of the table's parameter box, 10 % beyond each end (the clamp). */
static void random_point(const mf_table *t, mf_pcg32 *rng, double *p)
{
    for (int k = 0; k < t->naxes; ++k) {
        double lo = t->axes[k].lo, hi = t->axes[k].hi;
        p[k] = lo + (hi - lo) * (1.2 * mf_pcg32_next_double(rng) - 0.1);
    }
}

static double clamp_to_axis(const mf_table_axis *a, double p)
{
    double lo = fmin(a->lo, a->hi), hi = fmax(a->lo, a->hi);
    return p < lo ? lo : (p > hi ? hi : p);
}

/* 4 to 6 axes: create, record, and lookup, which reproduces a multilinear function.
 * Tolerance 1e-13 absolute (values up to ~10): a convex combination of 2^naxes records, each
 * exact to an ulp, with weights from a few roundings of the coordinates: ~ 2^6 ulp of 10. */
static void test_nd(void)
{
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(77), 1);
    const int sizes[MF_TABLE_MAX_AXES] = {5, 4, 3, 3, 2, 2};
    for (int naxes = 4; naxes <= MF_TABLE_MAX_AXES; ++naxes) {
        mf_table t;
        CHECK(nd_table(&t, naxes, sizes, &rng));
        if (!t.data)
            continue;
        /* texel centres: the stored record exactly */
        int idx[MF_TABLE_MAX_AXES] = {4, 1, 2, 0, 1, 1};
        double p[MF_TABLE_MAX_AXES], out[2];
        for (int k = 0; k < naxes; ++k)
            p[k] = mf_table_axis_param(&t.axes[k], idx[k]);
        CHECK(mf_table_lookup(&t, p, out) == MF_OK);
        CHECK(out[0] == mf_table_record(&t, idx)[0] && out[1] == mf_table_record(&t, idx)[1]);
        int bad[MF_TABLE_MAX_AXES] = {0, 0, 0, 0, 0, 0};
        bad[naxes - 1] = sizes[naxes - 1];
        CHECK(mf_table_record(&t, bad) == NULL);
        double worst = 0.0;
        for (int i = 0; i < 2000; ++i) {
            random_point(&t, &rng, p);
            CHECK(mf_table_lookup(&t, p, out) == MF_OK);
            double pc[MF_TABLE_MAX_AXES];
            for (int k = 0; k < naxes; ++k)
                pc[k] = clamp_to_axis(&t.axes[k], p[k]);
            worst = fmax(worst, fabs(out[0] - multilinear(pc, naxes)));
        }
        printf("%d axes: multilinear lookup worst |error| %.3g\n", naxes, worst);
        CHECK_ABS(worst, 0.0, 1e-13);
        mf_table_free(&t);
    }
    /* more axes than the maximum: refused */
    mf_table_axis ax[MF_TABLE_MAX_AXES + 1];
    for (int k = 0; k <= MF_TABLE_MAX_AXES; ++k) {
        char nm[8];
        snprintf(nm, sizeof nm, "x%d", k);
        ax[k] = axis(nm, nm, 2, 0.0, 1.0, MF_AXIS_IDENTITY, -INFINITY);
    }
    const char *one[1] = {"v"};
    mf_table t;
    CHECK(mf_table_create(&t, MF_TABLE_MAX_AXES + 1, ax, 1, one) == MF_ERR_DOMAIN);
}

/* The 2D atlas and its shader-style lookup against mf_table_lookup, 3 to 5 axes (and 6), random
 * values, 3000 random points each (10 % beyond the ends: the clamp).  Tolerance 1e-12 absolute
 * (values in [-1, 1]): both are convex combinations of the same records; they differ by the
 * rounding of the texel coordinate (through u = (col + uv) w / W and back, a few ulp of the atlas
 * width ~ 1e-14) times a neighbour difference <= 2, plus the summation order (2^naxes terms). */
static void test_atlas(void)
{
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(78), 2);
    const int sizes[MF_TABLE_MAX_AXES] = {7, 5, 4, 3, 3, 2};
    for (int naxes = 3; naxes <= MF_TABLE_MAX_AXES; ++naxes) {
        mf_table t;
        CHECK(nd_table(&t, naxes, sizes, &rng));
        if (!t.data)
            continue;
        for (int variant = 0; variant < 2; ++variant) {
            mf_table_atlas a;
            int tiles_x = variant == 0 ? 0 : 5; /* default (axis 2 along x), and 5 columns (unused tiles) */
            CHECK(mf_table_atlas_layout(&t, tiles_x, &a) == MF_OK);
            long tiles = 1;
            for (int k = 2; k < naxes; ++k)
                tiles *= sizes[k];
            CHECK(a.tile_w == 7 && a.tile_h == 5 && a.tiles == tiles && a.tiles_x * a.tiles_y >= tiles);
            CHECK(a.tiles_x == (variant == 0 ? 4 : (tiles < 5 ? (int)tiles : 5)));
            CHECK(a.width == 7 * a.tiles_x && a.height == 5 * a.tiles_y);
            double *img = malloc(sizeof *img * (size_t)a.width * (size_t)a.height * 2);
            CHECK(img != NULL);
            if (!img)
                continue;
            mf_table_atlas_fill(&t, &a, img);
            /* one texel by the documented formula: (i0, i1) = (3, 2) of the last tile; and an unused
             * tile's texel is 0 */
            {
                int tt = a.tiles - 1;
                int x = (tt % a.tiles_x) * 7 + 3, y = (tt / a.tiles_x) * 5 + 2;
                CHECK(img[((size_t)y * a.width + x) * 2 + 1] == t.data[((size_t)3 + 7 * 2 + 35 * (size_t)tt) * 2 + 1]);
                if (a.tiles_x * a.tiles_y > a.tiles)
                    CHECK(img[((size_t)a.height * a.width - 1) * 2 + 1] == 0.0);
            }
            /* metadata round trip */
            mf_table_atlas b;
            CHECK(variant == 1 || mf_table_atlas_from_meta(&t, &b) == MF_ERR_DOMAIN); /* none yet */
            CHECK(mf_table_atlas_record(&t, &a) == MF_OK);
            CHECK(mf_table_atlas_from_meta(&t, &b) == MF_OK && !memcmp(&a, &b, sizeof a));
            double worst = 0.0;
            for (int i = 0; i < 3000; ++i) {
                double p[MF_TABLE_MAX_AXES], x[2], y[2];
                random_point(&t, &rng, p);
                if (i < 64) /* exact texel centres too */
                    for (int k = 0; k < naxes; ++k)
                        p[k] = mf_table_axis_param(&t.axes[k], (int)(mf_pcg32_next_double(&rng) * sizes[k]));
                CHECK(mf_table_lookup(&t, p, x) == MF_OK);
                CHECK(mf_table_atlas_lookup(&t, &a, img, p, y) == MF_OK);
                worst = fmax(worst, fmax(fabs(x[0] - y[0]), fabs(x[1] - y[1])));
            }
            printf("%d axes, %d x %d tiles (%d x %d texels): atlas vs lookup worst |difference| %.3g\n", naxes,
                   a.tiles_x, a.tiles_y, a.width, a.height, worst);
            CHECK_ABS(worst, 0.0, 1e-12);
            double pn[MF_TABLE_MAX_AXES] = {0, 0, NAN, 0, 0, 0}, o[2];
            CHECK(mf_table_atlas_lookup(&t, &a, img, pn, o) == MF_ERR_DOMAIN);
            free(img);
        }
        mf_table_free(&t);
    }
    /* a layout that does not fit the table is refused */
    mf_table t;
    CHECK(nd_table(&t, 3, sizes, &rng));
    CHECK(mf_table_set_meta(&t, "atlas", "tiles_x=2 tiles_y=1 tile_w=7 tile_h=5 order=axis2_fastest") == MF_OK);
    mf_table_atlas b;
    CHECK(mf_table_atlas_from_meta(&t, &b) == MF_ERR_DOMAIN); /* 4 tiles do not fit 2 x 1 */
    mf_table_free(&t);
}

int main(void)
{
    test_nd();
    test_atlas();
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
