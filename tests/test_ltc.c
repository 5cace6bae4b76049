/*
 * test_ltc.c -- linearly transformed cosines (mf_ltc.h): normalisation, sampler, polygon
 * integral, docs/math.md corrections C-T2 to C-T4, the isotropic form and its frame, and the
 * sphere (cap) approximation.
 *
 * Quadrature: composite Gauss-Legendre product rules (mf_quad_gauss_legendre, 16 points per
 * panel) over smooth integrands only -- every kink (the support boundary (M^-1 w).z = 0 of D, the
 * horizon of a cap) is put on a panel edge -- so the rules converge like h^32 and their error is
 * at rounding level; tolerances state what limits them.
 *
 * Monte Carlo: integral over P of D is the probability that an LTC sample hits P, so the estimate
 * is the hit fraction of N = MC_N samples (hits by ray-plane intersection and a crossing-number
 * test: independent of the code under test), checked as |est - ref| <= z se + delta with the
 * binomial se = sqrt(ref (1 - ref) / N) of the reference, z = 4.5 (two-sided 6.8e-6 per check;
 * < 1e-3 false alarms over the ~60 checks) and delta = 5 / N (the normal approximation fails for
 * expected counts below ~10; P(Poisson(1) >= 6) = 6e-4).
 *
 * Chi-square test of the sampler: the harness of tests/test_sample.c (pooled cells with expected
 * count >= 5, Bonferroni over the cases, negative controls), with a grid adapted to the LTC:
 * rows uniform in mu = n.w and columns uniform in the azimuth around n, where n is the pole of
 * the support hemisphere of D (n = normalize(row 2 of M^-1)).  D is analytic inside that
 * hemisphere, so every cell integrand is smooth and a fixed product rule is exact to ~1e-13.
 */
#include "mf_test.h"
#include "test_polygon_mc.h"
#include "mf_stats.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_quad.h"
#include "mfkit/mf_rng.h"
#include "mfkit/mf_sample.h"

#include <float.h>
#include <string.h>

#define DEG (MF_PI / 180.0)
#define TWO_PI (2.0 * MF_PI)
#define GL 16
#define MC_N 400000
#define MC_Z 4.5
#define MC_DELTA (5.0 / MC_N)

static double gl_x[GL], gl_w[GL];

static mf_vec3 v3(double x, double y, double z) { return mf_vec3_make(x, y, z); }

static mf_ltc make_ltc(mf_mat3 m)
{
    mf_ltc l;
    mf_status st = mf_ltc_init(&l, m);
    CHECK(st == MF_OK);
    if (st != MF_OK)
        memset(&l, 0, sizeof l);
    return l;
}

static mf_mat3 mat(double a, double b, double c, double d, double e, double f, double g, double h, double i)
{
    double m[9] = {a, b, c, d, e, f, g, h, i};
    return mf_ltc_matrix_general(m);
}

/* The test matrices: well-conditioned ones (identity, isotropic GGX-like fits, a general
 * 9-parameter one, det < 0), and ill-conditioned ones (strong shear, anisotropy 1:1e3,
 * a near-specular lobe alpha ~ 1e-3). */
typedef struct {
    const char *name;
    mf_mat3 m;
    int well; /* condition number <= ~20 */
} test_matrix;

static int build_matrices(test_matrix *t)
{
    int n = 0;
    t[n++] = (test_matrix){"identity", mf_mat3_identity(), 1};
    t[n++] = (test_matrix){"isotropic a=0.5 b=0.2 c=0.5 d=-0.3", mf_ltc_matrix_isotropic(0.5, 0.2, 0.5, -0.3), 1};
    t[n++] = (test_matrix){"isotropic grazing a=0.3 b=0.9 c=0.4 d=-0.7", mf_ltc_matrix_isotropic(0.3, 0.9, 0.4, -0.7),
                           1};
    t[n++] = (test_matrix){"general", mat(0.8, 0.3, -0.2, -0.1, 0.6, 0.25, 0.3, -0.2, 1.1), 1};
    t[n++] = (test_matrix){"det<0 (x mirrored)", mat(-0.7, 0.1, 0.3, 0.2, 0.9, 0.0, 0.1, 0.2, 1.0), 1};
    t[n++] = (test_matrix){"lobe below the horizon", mat(1.0, 0.0, 0.5, 0.0, 1.0, 0.0, 0.0, 0.3, -0.6), 1};
    t[n++] = (test_matrix){"strong shear", mat(1.0, 40.0, 0.0, 0.0, 1.0, 25.0, 0.0, 0.0, 1.0), 0};
    t[n++] = (test_matrix){"anisotropic 1:1e3",
                           mf_mat3_mul(mf_test_rotation(v3(0.6, 0.0, 0.8), 0.4), mat(1e-3, 0, 0, 0, 1, 0, 0, 0, 1)), 0};
    t[n++] = (test_matrix){"near-specular alpha 1e-3, det<0", mat(-1e-3, 0, 2e-4, 0, 1e-3, 0, 5e-4, 0, 1.0), 0};
    return n;
}

/* ---- quadrature over a hemisphere ---------------------------------------------------------- */
typedef double (*sph_fn)(mf_vec3 w, void *user);

/* Integral over the hemisphere {w : n.w > 0} of f(w) dw, mu = n.w in `mp` panels, the azimuth
 * in `pp` panels, GL points each. */
static double hemisphere_rule(sph_fn f, void *user, mf_vec3 n, int mp, int pp)
{
    mf_frame fr = mf_frame_from_normal(n);
    double sum = 0.0;
    for (int a = 0; a < mp; ++a)
        for (int i = 0; i < GL; ++i) {
            double mu = (a + 0.5 * (1.0 + gl_x[i])) / mp, wm = gl_w[i] * 0.5 / mp;
            double st = sqrt(fmax(0.0, 1.0 - mu * mu));
            double inner = 0.0;
            for (int b = 0; b < pp; ++b)
                for (int j = 0; j < GL; ++j) {
                    double ph = TWO_PI * (b + 0.5 * (1.0 + gl_x[j])) / pp;
                    mf_vec3 w = mf_frame_to_world(fr, v3(st * cos(ph), st * sin(ph), mu));
                    inner += gl_w[j] * f(w, user);
                }
            sum += wm * inner * (MF_PI / pp);
        }
    return sum;
}

/* Pole of the support hemisphere (M^-1 w).z > 0 of D: row 2 of M^-1, normalised. */
static mf_vec3 support_pole(const mf_ltc *l)
{
    return mf_vec3_normalize(v3(l->inv.m[2][0], l->inv.m[2][1], l->inv.m[2][2]));
}

static double d_integrand(mf_vec3 w, void *user) { return mf_ltc_eval(user, w); }

/* In the pre-image: integral over wo (upper hemisphere) of D(w(wo)) |dw / dwo|,
 * w = M wo / |M wo|, |dw / dwo| = |det M| / |M wo|^3 (the forward Jacobian). */
static double preimage_integrand(mf_vec3 wo, void *user)
{
    const mf_ltc *l = user;
    mf_vec3 mw = mf_mat3_apply(l->m, wo);
    double r = mf_vec3_length(mw);
    return mf_ltc_eval(l, mf_vec3_scale(mw, 1.0 / r)) * fabs(l->det) / (r * r * r);
}

/* correction C-T2: integral of D over the sphere is 1 for every matrix, (a) in the pre-image, where the
 * integrand D(w(wo)) |dw/dwo| is wo.z / pi up to rounding -- this checks that eval's Jacobian is
 * the inverse of the forward one to ~cond(M) eps for any M; and (b) directly on the sphere for
 * the well-conditioned ones, over the support hemisphere (D is analytic there).  Tolerances:
 * (a) 1e-12 (cond(M) <= 1e3 here: the round trip w -> M^-1 w loses ~cond eps relative per node);
 * (b) 1e-11 (a 128 x 256-node rule on an analytic integrand; measured ~1e-15). */
static void test_normalisation(const test_matrix *t, int nt)
{
    double worst_pre = 0.0, worst_direct = 0.0;
    for (int k = 0; k < nt; ++k) {
        mf_ltc l = make_ltc(t[k].m);
        double pre = hemisphere_rule(preimage_integrand, &l, v3(0, 0, 1), 4, 8);
        CHECK_ABS(pre, 1.0, 1e-12);
        worst_pre = fmax(worst_pre, fabs(pre - 1.0));
        if (t[k].well) {
            double direct = hemisphere_rule(d_integrand, &l, support_pole(&l), 8, 16);
            CHECK_ABS(direct, 1.0, 1e-11);
            worst_direct = fmax(worst_direct, fabs(direct - 1.0));
        }
    }
    /* The printed D without the Jacobian (D_o(M^-1 w / |M^-1 w|) alone) is not normalised: */
    mf_ltc l = make_ltc(t[2].m);
    mf_vec3 n = support_pole(&l);
    double s = 0.0;
    for (int i = 0; i < 64; ++i) /* crude sum, enough to show a large deviation */
        for (int j = 0; j < 128; ++j) {
            double mu = (i + 0.5) / 64, ph = TWO_PI * (j + 0.5) / 128, st = sqrt(1.0 - mu * mu);
            mf_vec3 w = mf_frame_to_world(mf_frame_from_normal(n), v3(st * cos(ph), st * sin(ph), mu));
            mf_vec3 u = mf_mat3_apply(l.inv, w);
            s += fmax(0.0, u.z / mf_vec3_length(u)) * MF_INV_PI * (1.0 / 64) * (TWO_PI / 128);
        }
    CHECK(fabs(s - 1.0) > 0.1);
    printf("normalisation: %d matrices, worst |1 - integral| pre-image %.3g, direct (well-conditioned) %.3g; "
           "without the Jacobian: %.4f\n",
           nt, worst_pre, worst_direct, s);
}

/* Invariances and values: identity = cosine; M -> k M (k > 0) and M -> M R with R a rotation
 * about z or the mirror y -> -y (det < 0) leave D unchanged (D_o is invariant under them);
 * D = 0 outside the support; the world/local frame of the isotropic form. */
static void test_eval(mf_pcg32 *rng, const test_matrix *t, int nt)
{
    mf_ltc id = make_ltc(mf_mat3_identity());
    for (int k = 0; k < 100; ++k) {
        double u[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)};
        mf_vec3 w = mf_sample_uniform_sphere(u);
        CHECK_ABS(mf_ltc_eval(&id, w), fmax(0.0, w.z) * MF_INV_PI, 2 * DBL_EPSILON);
        for (int i = 0; i < nt; ++i) {
            mf_ltc l = make_ltc(t[i].m);
            double d = mf_ltc_eval(&l, w);
            mf_vec3 uo = mf_mat3_apply(l.inv, w);
            CHECK(d >= 0.0 && (uo.z > 0.0 ? d > 0.0 : d == 0.0));
            /* rounding of w and of u = M^-1 w, amplified by |u|^-4 (cond(M) <= ~1e4 here) and, in
             * the factor u.z, by |u| / u.z near the edge of the support */
            double tol = (t[i].well ? 32 * DBL_EPSILON : 1e-11) * (1.0 + mf_vec3_length(uo) / uo.z);
            CHECK_REL(mf_ltc_eval(&l, mf_vec3_scale(w, 3.7)), d, tol);
            if (!(d > 0.0))
                continue;
            mf_mat3 scaled = t[i].m;
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c)
                    scaled.m[r][c] *= 2.5;
            mf_ltc ls = make_ltc(scaled);
            CHECK_REL(mf_ltc_eval(&ls, w), d, tol);
            mf_ltc lr = make_ltc(mf_mat3_mul(t[i].m, mf_test_rotation(v3(0, 0, 1), 1.3)));
            CHECK_REL(mf_ltc_eval(&lr, w), d, tol);
            mf_ltc lm = make_ltc(mf_mat3_mul(t[i].m, mat(1, 0, 0, 0, -1, 0, 0, 0, 1)));
            CHECK(lm.det * l.det < 0.0);
            CHECK_REL(mf_ltc_eval(&lm, w), d, tol);
        }
    }
    /* -M mirrors the lobe through the origin */
    mf_ltc l = make_ltc(t[1].m), ln = make_ltc(mat(-0.5, 0, -0.2, 0, -0.5, 0, 0.3, 0, -1));
    mf_vec3 w = mf_vec3_normalize(v3(0.3, 0.1, 0.9));
    CHECK_REL(mf_ltc_eval(&ln, mf_vec3_scale(w, -1.0)), mf_ltc_eval(&l, w), 1e-13);

    /* domain */
    mf_ltc bad;
    CHECK(mf_ltc_init(&bad, mat(1, 0, 0, 0, 1, 0, 0, 0, 0)) == MF_ERR_DOMAIN);
    CHECK(mf_ltc_init(&bad, mat(1, 2, 3, 2, 4, 6, 0, 0, 1)) == MF_ERR_DOMAIN); /* rank 2 */
    CHECK(mf_ltc_init(&bad, mat(NAN, 0, 0, 0, 1, 0, 0, 0, 1)) == MF_ERR_DOMAIN);
    CHECK(mf_ltc_init(&bad, mat(INFINITY, 0, 0, 0, 1, 0, 0, 0, 1)) == MF_ERR_DOMAIN);
    CHECK(mf_ltc_init(&bad, mat(1e-200, 0, 0, 0, 1e-200, 0, 0, 0, 1)) == MF_ERR_DOMAIN); /* 1/det overflows */
    CHECK(mf_ltc_init(NULL, mf_mat3_identity()) == MF_ERR_DOMAIN);
    CHECK(isnan(mf_ltc_eval(&l, v3(0, 0, 0))) && isnan(mf_ltc_eval(&l, v3(NAN, 0, 1))));
    /* the stored inverse and determinant */
    for (int i = 0; i < nt; ++i) {
        mf_ltc li = make_ltc(t[i].m);
        mf_mat3 p = mf_mat3_mul(li.m, li.inv);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c)
                CHECK_ABS(p.m[r][c], r == c ? 1.0 : 0.0, t[i].well ? 1e-14 : 1e-11);
        CHECK_REL(li.abs_det_inv * fabs(li.det), 1.0, 4 * DBL_EPSILON);
    }
}

/* The isotropic form in its view frame: the frame puts wo in the +x half of the xz plane, and the
 * world matrix R M gives D_world(w) = D_local(local(w)) and the same polygon integrals. */
static void test_view_frame(mf_pcg32 *rng)
{
    static const double thetas[] = {0.0, 30.0, 75.0, 89.9};
    mf_mat3 ml = mf_ltc_matrix_isotropic(0.4, 0.3, 0.45, -0.5);
    CHECK(ml.m[0][0] == 0.4 && ml.m[0][2] == 0.3 && ml.m[1][1] == 0.45 && ml.m[2][0] == -0.5 && ml.m[2][2] == 1.0 &&
          ml.m[0][1] == 0.0 && ml.m[1][0] == 0.0 && ml.m[1][2] == 0.0 && ml.m[2][1] == 0.0);
    for (int it = 0; it < 4; ++it) {
        mf_vec3 wo = mf_vec3_spherical(thetas[it] * DEG, 2.2);
        mf_frame f = mf_ltc_view_frame(wo);
        mf_vec3 lo = mf_frame_to_local(f, wo);
        CHECK_ABS(lo.y, 0.0, 4 * DBL_EPSILON);
        CHECK(lo.x >= 0.0);
        CHECK_ABS(lo.z, wo.z, 4 * DBL_EPSILON);
        mf_ltc local = make_ltc(ml), world = make_ltc(mf_ltc_matrix_to_world(f, ml));
        for (int k = 0; k < 50; ++k) {
            double u[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)};
            mf_vec3 w = mf_sample_uniform_sphere(u);
            CHECK_REL(mf_ltc_eval(&world, w), mf_ltc_eval(&local, mf_frame_to_local(f, w)), 1e-13);
        }
        mf_vec3 v[4] = {v3(1, 2, -0.5), v3(1, 2, 1.5), v3(-1, 2, 1.5), v3(-1, 2, -0.5)};
        mf_polygon pw = mf_polygon_make(4, v), pl = pw;
        for (int i = 0; i < 4; ++i)
            pl.v[i] = mf_frame_to_local(f, pw.v[i]);
        CHECK_REL(mf_ltc_integrate_polygon(&world, &pw, MF_POLYGON_TWO_SIDED),
                  mf_ltc_integrate_polygon(&local, &pl, MF_POLYGON_TWO_SIDED), 1e-13);
    }
    mf_frame f0 = mf_ltc_view_frame(v3(0, 0, 1));
    CHECK(f0.s.x == 1.0 && f0.t.y == 1.0 && f0.n.z == 1.0);
    CHECK(isnan(mf_ltc_view_frame(v3(NAN, 0, 1)).s.x));
}

/* ---- Monte Carlo: polygon integrals ---------------------------------------------------------- */
static double mc_ltc(const mf_ltc *l, const mf_polygon *p, mf_pcg32 *rng)
{
    long hits = 0;
    for (long k = 0; k < MC_N; ++k) {
        double u[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)};
        hits += mf_test_ray_hits(p, mf_ltc_sample(l, u));
    }
    return (double)hits / MC_N;
}

static double binomial_se(double p) { return sqrt(fmax(0.0, p * (1.0 - p)) / MC_N); }

/* A random planar polygon (3..8 vertices, star-shaped around its centre c). */
static mf_polygon random_polygon(mf_pcg32 *rng, mf_vec3 c, double size)
{
    double u[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)};
    mf_vec3 nrm = mf_vec3_normalize(mf_vec3_add(c, mf_vec3_scale(mf_sample_uniform_sphere(u), 0.9)));
    if (mf_vec3_dot(nrm, c) < 0.35)
        nrm = c;
    mf_frame f = mf_frame_from_normal(nrm);
    int n = 3 + (int)(mf_pcg32_next_double(rng) * 6.0);
    mf_vec3 v[8];
    for (int i = 0; i < n; ++i) {
        double a = TWO_PI * (i + 0.8 * mf_pcg32_next_double(rng)) / n;
        double r = size * (0.2 + 0.8 * mf_pcg32_next_double(rng)) * ((i % 2 && n > 4) ? 0.5 : 1.0);
        v[i] = mf_vec3_add(c, mf_frame_to_world(f, v3(r * cos(a), r * sin(a), 0.0)));
    }
    mf_polygon p = mf_polygon_make(n, v);
    return (mf_pcg32_next_u32(rng) & 1u) ? mf_test_reversed(&p) : p;
}

/* The polygon integral against Monte Carlo with the LTC's own sampler, for every test matrix and
 * random polygons around the lobe: above, across and below the horizon. */
static void test_polygon_mc(mf_pcg32 *rng, const test_matrix *t, int nt)
{
    double worst_z = 0.0, worst_abs = 0.0;
    int checks = 0, below = 0;
    for (int k = 0; k < nt; ++k) {
        mf_ltc l = make_ltc(t[k].m);
        for (int j = 0; j < 5; ++j) {
            /* centre: near the lobe's peak direction M z, or anywhere */
            double u[2] = {mf_pcg32_next_double(rng), mf_pcg32_next_double(rng)};
            mf_vec3 c = (j < 3) ? mf_ltc_sample(&l, u) : mf_sample_uniform_sphere(u);
            double size = (j == 1) ? 0.05 : 0.2 + mf_pcg32_next_double(rng);
            mf_polygon p = random_polygon(rng, c, size);
            int all_below = 1;
            for (int i = 0; i < p.n; ++i)
                all_below = all_below && p.v[i].z < 0.0;
            below += all_below;
            double ref = mf_ltc_integrate_polygon(&l, &p, MF_POLYGON_TWO_SIDED);
            double est = mc_ltc(&l, &p, rng), se = binomial_se(ref);
            CHECK_MC(est, se, ref, MC_Z, MC_DELTA);
            ++checks;
            if (se > 0.0)
                worst_z = fmax(worst_z, fabs(est - ref) / se);
            worst_abs = fmax(worst_abs, fabs(est - ref));
            /* one-sided: all or nothing, by the facing of p (not of M^-1 p: det M < 0 flips it) */
            double one = mf_ltc_integrate_polygon(&l, &p, MF_POLYGON_ONE_SIDED);
            double facing = mf_polygon_solid_angle_signed(&p);
            CHECK(facing > 0.0 ? one == ref : one == 0.0);
        }
    }
    printf("ltc polygon integral vs monte carlo: %d cases (%d polygons entirely below the horizon), N = %d: worst "
           "|est - I| = %.3g, worst |est - I| / se = %.2f\n",
           checks, below, MC_N, worst_abs, worst_z);
}

/* Sutherland-Hodgman against z >= 0 on the raw vertices (for the wrong "clip before" variant). */
static mf_polygon clip_z(const mf_polygon *p)
{
    mf_vec3 out[16];
    int m = 0;
    for (int i = 0; i < p->n; ++i) {
        mf_vec3 a = p->v[i], b = p->v[(i + 1) % p->n];
        if (a.z >= 0.0)
            out[m++] = a;
        if ((a.z > 0.0) != (b.z > 0.0) && a.z != 0.0 && b.z != 0.0) {
            double s = a.z / (a.z - b.z);
            out[m++] = v3(a.x + s * (b.x - a.x), a.y + s * (b.y - a.y), 0.0);
        }
    }
    mf_polygon r;
    memset(&r, 0, sizeof r);
    if (m >= 3 && m <= MF_POLYGON_MAX_VERTICES)
        r = mf_polygon_make(m, out);
    return r;
}

/* corrections C-T3 and C-T4, each with a check that fails on the printed or wrong form. */
static void test_errata(mf_pcg32 *rng)
{
    /* C-T3: identity M.  The integral of D over P is E(P) of the normalised cosine max(0,z)/pi
     * (= hit fraction of cosine samples), not the irradiance E_cos = pi E. */
    mf_ltc id = make_ltc(mf_mat3_identity());
    mf_vec3 tv[4] = {v3(-0.4, -0.3, 0.6), v3(0.7, -0.2, 0.6), v3(0.6, 0.8, 0.6), v3(-0.5, 0.6, 0.6)};
    mf_polygon p = mf_polygon_make(4, tv);
    double i_ltc = mf_ltc_integrate_polygon(&id, &p, MF_POLYGON_TWO_SIDED);
    double e = mf_polygon_integrate_cosine(&p, MF_POLYGON_TWO_SIDED);
    CHECK_REL(i_ltc, e, 4 * DBL_EPSILON);
    double est = mc_ltc(&id, &p, rng);
    CHECK_MC(est, binomial_se(i_ltc), i_ltc, MC_Z, MC_DELTA);
    double printed = MF_PI * e; /* "E = irradiance" of the printed Eq. 2.33 */
    CHECK(fabs(est - printed) > 100.0 * binomial_se(i_ltc));
    printf("correction C-T3: identity M: integral %.6f = E_cos/pi (E_cos = %.6f), MC %.6f\n", i_ltc, printed, est);

    /* C-T4: a sheared M (the isotropic form at a grazing view: its lobe leans to +x and reaches
     * below the horizon) and a vertical quad crossing the horizon.  Clipping P at the shading
     * horizon before the transform gives a different (wrong) value; Monte Carlo decides. */
    mf_ltc gr = make_ltc(mf_ltc_matrix_isotropic(0.3, 0.9, 0.4, -0.7));
    mf_vec3 qv[4] = {v3(1.0, 1.0, -1.0), v3(1.0, 1.0, 1.2), v3(1.0, -1.0, 1.2), v3(1.0, -1.0, -1.0)};
    mf_polygon quad = mf_polygon_make(4, qv);
    double right = mf_ltc_integrate_polygon(&gr, &quad, MF_POLYGON_TWO_SIDED);
    mf_polygon clipped = clip_z(&quad);
    double wrong = mf_ltc_integrate_polygon(&gr, &clipped, MF_POLYGON_TWO_SIDED);
    est = mc_ltc(&gr, &quad, rng);
    CHECK_MC(est, binomial_se(right), right, MC_Z, MC_DELTA);
    CHECK(fabs(est - wrong) > 20.0 * binomial_se(right));
    printf("correction C-T4: sheared M, vertical quad: clip after M^-1 %.6f, clip before %.6f, MC %.6f\n", right, wrong, est);

    /* ... and a triangle entirely below the horizon still receives light from a lobe that
     * reaches below it: clip-before gives 0. */
    mf_ltc sh = make_ltc(mat(1.0, 0.0, 0.6, 0.0, 0.8, 0.3, -0.7, 0.2, 0.5));
    mf_vec3 bv[3] = {v3(1.0, -0.5, -0.05), v3(1.0, 0.5, -0.05), v3(1.0, 0.0, -0.6)};
    mf_polygon tri = mf_polygon_make(3, bv);
    double below = mf_ltc_integrate_polygon(&sh, &tri, MF_POLYGON_TWO_SIDED);
    est = mc_ltc(&sh, &tri, rng);
    CHECK(below > 1e-3);
    CHECK(clip_z(&tri).n == 0); /* nothing left to integrate when clipping first */
    CHECK_MC(est, binomial_se(below), below, MC_Z, MC_DELTA);
    printf("correction C-T4: triangle below the horizon: %.6f (clip before: 0), MC %.6f\n", below, est);
}

/* ---- chi-square test of the sampler ----------------------------------------------------------
 * (Q(a, x) and the p-value from tests/mf_stats.h.) */
#define N_MU 20
#define N_PHI 40
#define N_CELLS (N_MU * N_PHI)
#define N_SAMPLES 200000
#define MIN_EXPECTED 5.0
#define ALPHA_TOTAL 0.01

typedef struct chi2_result {
    double chi2, pvalue, integral, quad_diff;
    int dof;
    long bad_samples, outside;
} chi2_result;

/* Cell integral of pdf over mu = cos(theta) in [m0, m1], phi in [p0, p1] around the frame fr, with
 * dw = sin(theta) dtheta dphi: in theta (not mu) the integrand is analytic up to the pole (in mu
 * it would have a sqrt(1 - mu) term there).  A product rule of panels x panels GL panels. */
static double cell_rule(const mf_ltc *pdf, mf_frame fr, double m0, double m1, double p0, double p1, int panels)
{
    double t0 = acos(m1), t1 = acos(m0);
    double s = 0.0, ht = (t1 - t0) / panels, hp = (p1 - p0) / panels;
    for (int a = 0; a < panels; ++a)
        for (int i = 0; i < GL; ++i) {
            double th = t0 + ht * (a + 0.5 * (1.0 + gl_x[i])), st = sin(th), ct = cos(th);
            for (int b = 0; b < panels; ++b)
                for (int j = 0; j < GL; ++j) {
                    double ph = p0 + hp * (b + 0.5 * (1.0 + gl_x[j]));
                    mf_vec3 w = mf_frame_to_world(fr, v3(st * cos(ph), st * sin(ph), ct));
                    s += 0.25 * ht * hp * gl_w[i] * gl_w[j] * st * mf_ltc_eval(pdf, w);
                }
        }
    return s;
}

static chi2_result chi2_test(const mf_ltc *sampler, const mf_ltc *pdf, uint64_t seed, uint64_t stream)
{
    static double expected[N_CELLS];
    static long observed[N_CELLS];
    static int order[N_CELLS];
    chi2_result r;
    memset(&r, 0, sizeof r);
    mf_frame fr = mf_frame_from_normal(support_pole(pdf));
    for (int i = 0; i < N_MU; ++i)
        for (int j = 0; j < N_PHI; ++j) {
            double m0 = (double)i / N_MU, m1 = (double)(i + 1) / N_MU;
            double p0 = TWO_PI * j / N_PHI, p1 = TWO_PI * (j + 1) / N_PHI;
            double v1 = cell_rule(pdf, fr, m0, m1, p0, p1, 1), v2 = cell_rule(pdf, fr, m0, m1, p0, p1, 2);
            r.quad_diff += fabs(v2 - v1);
            r.integral += v2;
            expected[i * N_PHI + j] = v2 * N_SAMPLES;
        }
    memset(observed, 0, sizeof observed);
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, stream);
    for (long n = 0; n < N_SAMPLES; ++n) {
        double u[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)};
        mf_vec3 w = mf_ltc_sample(sampler, u);
        if (!mf_vec3_isfinite(w) || !(fabs(mf_vec3_length(w) - 1.0) <= 1e-12)) {
            r.bad_samples++;
            continue;
        }
        mf_vec3 lw = mf_frame_to_local(fr, w);
        if (!(lw.z >= 0.0)) {
            r.outside++;
            continue;
        }
        int i = (int)(lw.z * N_MU);
        i = i >= N_MU ? N_MU - 1 : i;
        observed[i * N_PHI + chi2_phi_cell(lw.y, lw.x, N_PHI)]++;
    }
    chi2_pooled p = chi2_pool(expected, observed, order, N_CELLS, MIN_EXPECTED);
    r.chi2 = p.chi2;
    r.dof = p.dof;
    r.outside += p.zero_hits;
    r.pvalue = gamma_q(0.5 * r.dof, 0.5 * r.chi2);
    return r;
}

static void test_sampler_chi2(const test_matrix *t, int nt, uint64_t seed)
{
    int ncase = 0;
    for (int k = 0; k < nt; ++k)
        ncase += t[k].well;
    const double threshold = ALPHA_TOTAL / ncase;
    printf("chi-square: %d matrices, N = %d, %d x %d cells around the support pole, reject at p < %.3g\n", ncase,
           N_SAMPLES, N_MU, N_PHI, threshold);
    for (int k = 0; k < nt; ++k) {
        if (!t[k].well)
            continue; /* peaked lobes fall in a few cells of this grid: no power, tested by MC above */
        mf_ltc l = make_ltc(t[k].m);
        chi2_result r = chi2_test(&l, &l, seed, 10u + (uint64_t)k);
        printf("  %-44s X2 %8.2f dof %3d p %.4f |int - 1| %.1e quad diff %.1e\n", t[k].name, r.chi2, r.dof, r.pvalue,
               fabs(r.integral - 1.0), r.quad_diff);
        ++mf_test_checks;
        if (!(r.pvalue >= threshold))
            MF_FAIL_AT("%s: chi-square rejects: X2 = %.3f, dof = %d, p = %.3g < %.3g", t[k].name, r.chi2, r.dof,
                       r.pvalue, threshold);
        CHECK(r.bad_samples == 0 && r.outside == 0);
        /* The 2-panel rule's error is below |v2 - v1| (summed: quad diff); both ~1e-12 */
        CHECK(r.quad_diff < 1e-8);
        CHECK_ABS(r.integral, 1.0, 1e-8);
    }
    /* negative controls: slightly wrong pdfs must be rejected */
    struct {
        const char *name;
        mf_mat3 s, p;
    } neg[] = {
        {"a=0.5 samples vs a=0.55 pdf", mf_ltc_matrix_isotropic(0.5, 0.2, 0.5, -0.3),
         mf_ltc_matrix_isotropic(0.55, 0.2, 0.5, -0.3)},
        {"d=-0.3 samples vs d=-0.2 pdf", mf_ltc_matrix_isotropic(0.5, 0.2, 0.5, -0.3),
         mf_ltc_matrix_isotropic(0.5, 0.2, 0.5, -0.2)},
        {"M samples vs M^T pdf", mat(0.8, 0.3, -0.2, -0.1, 0.6, 0.25, 0.3, -0.2, 1.1),
         mf_mat3_transpose(mat(0.8, 0.3, -0.2, -0.1, 0.6, 0.25, 0.3, -0.2, 1.1))},
    };
    for (int k = 0; k < 3; ++k) {
        mf_ltc ls = make_ltc(neg[k].s), lp = make_ltc(neg[k].p);
        chi2_result r = chi2_test(&ls, &lp, seed, 100u + (uint64_t)k);
        printf("  negative control %-40s X2 %10.1f dof %3d p %.3g (outside %ld)\n", neg[k].name, r.chi2, r.dof,
               r.pvalue, r.outside);
        ++mf_test_checks;
        if (!(r.pvalue < threshold || r.outside > 0))
            MF_FAIL_AT("negative control not rejected: %s: p = %.3g", neg[k].name, r.pvalue);
    }
}

/* Sampler at the corners of [0,1)^2 and for ill-conditioned matrices: finite unit vectors inside
 * the support, with a finite positive pdf. */
static void test_sampler_extremes(const test_matrix *t, int nt)
{
    static const double corners[5][2] = {{0.0, 0.0}, {0x1.fffffffffffffp-1, 0x1.fffffffffffffp-1}, {0.0, 0.5},
                                         {0.5, 0.0}, {0.5, 0.5}};
    for (int k = 0; k < nt; ++k) {
        mf_ltc l = make_ltc(t[k].m);
        for (int c = 0; c < 5; ++c) {
            mf_vec3 w = mf_ltc_sample(&l, corners[c]);
            double p = mf_ltc_pdf(&l, w);
            CHECK(mf_vec3_isfinite(w) && fabs(mf_vec3_length(w) - 1.0) <= 1e-12 && isfinite(p) && p >= 0.0);
        }
    }
}

/* ---- the sphere (cap) approximation ---------------------------------------------------------
 * Brute force: integral of max(0, z)/pi over the cap of angular radius sigma centred at polar
 * angle theta_c, in polar coordinates (t, p) around the centre: z = cos t cos(theta_c) -
 * sin t sin(theta_c) cos p.  For each t the kink z = 0 is at cos p = cot t cot theta_c (a panel
 * edge of the inner rule), and the outer integrand is smooth except at t = |pi/2 - theta_c|
 * (where the kink appears), a panel edge of the outer rule. */
static double cap_inner(double t, double tc)
{
    /* z = a - b cos p grows with p in [0, pi] (b >= 0): z > 0 on (lo, pi], cos(lo) = a / b */
    double a = cos(t) * cos(tc), b = sin(t) * sin(tc), lo;
    if (b > 0.0)
        lo = (a / b >= 1.0) ? 0.0 : (a / b <= -1.0 ? MF_PI : acos(a / b));
    else
        lo = a > 0.0 ? 0.0 : MF_PI;
    double s = 0.0;
    for (int pan = 0; pan < 4; ++pan) {
        double l0 = lo + (MF_PI - lo) * pan / 4, l1 = lo + (MF_PI - lo) * (pan + 1) / 4;
        for (int i = 0; i < GL; ++i) {
            double p = l0 + 0.5 * (l1 - l0) * (1.0 + gl_x[i]);
            s += 0.5 * (l1 - l0) * gl_w[i] * fmax(0.0, a - b * cos(p));
        }
    }
    return 2.0 * s * sin(t) * MF_INV_PI; /* p in [0, 2 pi) by symmetry; dw = sin t dt dp */
}

static double cap_brute(double sigma, double tc)
{
    double pts[3] = {0.0, sigma, sigma};
    int n = 2;
    double tk = fabs(0.5 * MF_PI - tc);
    if (tk > 0.0 && tk < sigma) {
        pts[1] = tk;
        pts[2] = sigma;
        n = 3;
    }
    /* The inner integral behaves like (t - tk)^(3/2) at the kink radius tk (the arc z > 0
     * appears with a square-root length): t = a + (b - a)(1 - cos(pi v))/2 on each piece makes
     * t - a and b - t ~ v^2, so the integrand in v is smooth at both ends. */
    double s = 0.0;
    for (int seg = 0; seg + 1 < n; ++seg) {
        double a = pts[seg], b = pts[seg + 1];
        for (int pan = 0; pan < 8; ++pan)
            for (int i = 0; i < GL; ++i) {
                double v = (pan + 0.5 * (1.0 + gl_x[i])) / 8, wv = gl_w[i] * 0.5 / 8;
                double t = a + 0.5 * (b - a) * (1.0 - cos(MF_PI * v));
                s += wv * 0.5 * (b - a) * MF_PI * sin(MF_PI * v) * cap_inner(t, tc);
            }
    }
    return s;
}

/* The closed form against brute-force quadrature over caps of radius 1e-3 to pi/2, centres from
 * the zenith to the nadir; absolute 1e-15 + relative 1e-11 (the quadrature is at rounding level;
 * the rearranged formula keeps ~all digits even for tiny caps cut by the horizon). */
static void test_sphere_integral(void)
{
    static const double sigmas[] = {1e-3, 0.01, 0.1, 0.5, 1.0, 1.4, 0.5 * MF_PI - 1e-6, 0.5 * MF_PI};
    double worst = 0.0, worst_sig = 0.0, worst_tc = 0.0, worst_ref = 0.0;
    for (int is = 0; is < 8; ++is)
        for (int it = 0; it <= 24; ++it) {
            double sig = sigmas[is];
            /* centres on a grid, plus near the horizon at the scale of the radius */
            double tc = (it < 19) ? MF_PI * it / 18 : 0.5 * MF_PI + sig * (it - 21.5) / 3.0;
            if (!(tc >= 0.0 && tc <= MF_PI))
                continue;
            /* the reference uses the radius that s2 represents: near pi/2, sin^2 rounds away
             * ~1e-16 / (pi/2 - sigma) of the radius (1e-10 for pi/2 - 1e-6); 1 - s2 is exact */
            double s2 = sin(sig) * sin(sig);
            double got = mf_ltc_sphere_integral(s2, cos(tc));
            double ref = cap_brute(atan2(sqrt(s2), sqrt(1.0 - s2)), tc);
            double err = fabs(got - ref);
            CHECK(err <= 1e-15 + 1e-11 * ref);
            if (!(err <= 1e-15 + 1e-11 * ref))
                fprintf(stderr, "  sphere integral sigma=%.17g theta_c=%.17g: %.17g vs %.17g\n", sig, tc, got, ref);
            if (ref > 0.0 && err / ref > worst) {
                worst = err / ref;
                worst_sig = sig;
                worst_tc = tc;
                worst_ref = ref;
            }
        }
    printf("sphere integral vs brute force: worst relative error %.3g (sigma %.3g, theta_c %.6g, value %.3g)\n", worst,
           worst_sig, worst_tc, worst_ref);
    /* F of a cap: its unclipped integral is sin^2(sigma) cos(theta_c) = F.z */
    CHECK_REL(mf_ltc_sphere_integral(0.25, 0.9), 0.225, 2 * DBL_EPSILON);
    CHECK(mf_ltc_sphere_integral(0.25, -0.9) == 0.0);
    CHECK_REL(mf_ltc_sphere_integral(1.0, 1.0), 1.0, 2 * DBL_EPSILON);
    CHECK(mf_ltc_sphere_integral(0.0, 0.3) == 0.0);
    CHECK_REL(mf_ltc_sphere_integral(1.0 + 1e-13, 1.0), 1.0, 2 * DBL_EPSILON);
    CHECK(isnan(mf_ltc_sphere_integral(1.01, 0.5)) && isnan(mf_ltc_sphere_integral(-0.1, 0.5)));
    CHECK(isnan(mf_ltc_sphere_integral(0.5, 1.5)) && isnan(mf_ltc_sphere_integral(NAN, 0.5)));
    /* continuity across the switch between the cases (cos^2 theta = sin^2 sigma) */
    double s2 = 0.3, c = sqrt(s2);
    CHECK_ABS(mf_ltc_sphere_integral(s2, c * (1.0 - 1e-12)), mf_ltc_sphere_integral(s2, c), 1e-11);
    CHECK_ABS(mf_ltc_sphere_integral(s2, -c * (1.0 - 1e-12)), 0.0, 1e-11);
}

/* The clipless polygon approximation: equal to the exact integral when the equivalent cap is
 * above the horizon; close otherwise (documented as an approximation). */
static void test_polygon_sphere(void)
{
    mf_ltc l = make_ltc(mf_ltc_matrix_isotropic(0.5, 0.2, 0.5, -0.3));
    mf_vec3 v[4] = {v3(-0.3, -0.2, 1), v3(0.3, -0.2, 1), v3(0.3, 0.3, 1), v3(-0.3, 0.3, 1)};
    mf_polygon p = mf_polygon_make(4, v), r = mf_test_reversed(&p);
    double exact = mf_ltc_integrate_polygon(&l, &p, MF_POLYGON_TWO_SIDED);
    CHECK_REL(mf_ltc_integrate_polygon_sphere(&l, &p, MF_POLYGON_TWO_SIDED), exact, 1e-13);
    CHECK_REL(mf_ltc_integrate_polygon_sphere(&l, &r, MF_POLYGON_TWO_SIDED), exact, 1e-13);
    double f1 = mf_ltc_integrate_polygon_sphere(&l, &p, MF_POLYGON_ONE_SIDED);
    double f2 = mf_ltc_integrate_polygon_sphere(&l, &r, MF_POLYGON_ONE_SIDED);
    CHECK((f1 == 0.0) != (f2 == 0.0));
    CHECK_ABS(f1, mf_ltc_integrate_polygon(&l, &p, MF_POLYGON_ONE_SIDED), 1e-13);
    CHECK_ABS(f2, mf_ltc_integrate_polygon(&l, &r, MF_POLYGON_ONE_SIDED), 1e-13);
    /* det < 0: the facing is that of p */
    mf_ltc lm = make_ltc(mf_mat3_mul(mf_ltc_matrix_isotropic(0.5, 0.2, 0.5, -0.3), mat(1, 0, 0, 0, -1, 0, 0, 0, 1)));
    CHECK_ABS(mf_ltc_integrate_polygon_sphere(&lm, &p, MF_POLYGON_ONE_SIDED), f1, 1e-13);
    /* a quad crossing the horizon: an approximation, within 0.02 of the exact value here */
    mf_vec3 q[4] = {v3(1, 1, -0.3), v3(1, 1, 0.8), v3(-1, 1, 0.8), v3(-1, 1, -0.3)};
    mf_polygon pq = mf_polygon_make(4, q);
    double ex = mf_ltc_integrate_polygon(&l, &pq, MF_POLYGON_TWO_SIDED);
    double ap = mf_ltc_integrate_polygon_sphere(&l, &pq, MF_POLYGON_TWO_SIDED);
    printf("clipless approximation, quad across the horizon: exact %.6f, sphere %.6f\n", ex, ap);
    CHECK(fabs(ap - ex) < 0.02 && ap > 0.0);
}

int main(void)
{
    uint64_t seed = mf_test_seed(0x4c54435f74657374ULL);
    CHECK(mf_quad_gauss_legendre(GL, gl_x, gl_w) == MF_OK);
    test_matrix t[16];
    int nt = build_matrices(t);
    mf_pcg32 rng;

    test_normalisation(t, nt);
    mf_pcg32_seed(&rng, seed, 1);
    test_eval(&rng, t, nt);
    mf_pcg32_seed(&rng, seed, 2);
    test_view_frame(&rng);
    test_sphere_integral();
    test_polygon_sphere();
    test_sampler_extremes(t, nt);
    mf_pcg32_seed(&rng, seed, 3);
    test_errata(&rng);
    mf_pcg32_seed(&rng, seed, 4);
    test_polygon_mc(&rng, t, nt);
    test_sampler_chi2(t, nt, seed);
    MF_TEST_MAIN_END();
}
