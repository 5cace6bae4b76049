/* test_ltcfit_mask_cells.c -- the containment sets of the prefilter's fits (mf_ltcfit_aniso.c,
 * use_masks): the cell path (directions sorted into cells, whole cells decided by cap proofs, the
 * rest tested two at a time) against the direct test of every direction against every light
 * (mask_light), through mf_ltcfit_aniso_mask_compare.  The cell path promises the same sets, so
 * every comparison is exact (memcmp).  Directions are placed where a wrong proof or a reordered dot
 * product shows: on the lights' edges (the normalised vertices and edge midpoints, whose edge-plane
 * dot products are rounding noise of either sign), on their bounding caps' rims, in tight clusters
 * (cells far smaller than the lights), behind the lobe axis, not unit, and all identical. */
#include "mf_test.h"

#include <string.h>

#include "mfkit/fit/mf_ltcfit_aniso.h"
#include "mfkit/mf_rng.h"
#include "mfkit/mfkit.h"

#define NL 64
#define NMAX 20000

static mf_vec3 rnd_unit(mf_pcg32 *r)
{
    double z = 2.0 * mf_pcg32_next_double(r) - 1.0, ph = 2.0 * MF_PI * mf_pcg32_next_double(r);
    double s = sqrt(fmax(0.0, 1.0 - z * z));
    return mf_vec3_make(s * cos(ph), s * sin(ph), z);
}

/* d tilted from the unit a by about `ang` radians in a random direction. */
static mf_vec3 tilt(mf_pcg32 *r, mf_vec3 a, double ang)
{
    mf_vec3 q = rnd_unit(r);
    mf_vec3 t = mf_vec3_cross(a, q);
    double tl = mf_vec3_length(t);
    if (!(tl > 1e-9))
        return a;
    return mf_vec3_normalize(mf_vec3_add(a, mf_vec3_scale(t, tan(ang) / tl)));
}

static int popcount64(uint64_t m) { return __builtin_popcountll(m); }

/* Lights about the axis: regular n-gons (3, 4, 8 vertices) of radius 0.005 .. 2.5 rad (the largest
 * beyond a hemisphere: no cap pre-test) centred near the axis or anywhere. */
static int make_lights(mf_pcg32 *r, mf_vec3 axis, double spread, int *nv, double *verts)
{
    static const int shapes[3] = {3, 4, 8};
    double *v = verts;
    for (int k = 0; k < NL; ++k) {
        int n = shapes[k % 3];
        double rho = 0.005 * pow(500.0, mf_pcg32_next_double(r));
        mf_vec3 c = k % 4 == 3 ? rnd_unit(r) : tilt(r, axis, spread * 3.0 * mf_pcg32_next_double(r));
        mf_vec3 t1 = mf_vec3_normalize(mf_vec3_cross(c, fabs(c.z) < 0.9 ? mf_vec3_make(0, 0, 1) : mf_vec3_make(1, 0, 0)));
        mf_vec3 t2 = mf_vec3_cross(c, t1);
        double ph0 = mf_pcg32_next_double(r), tr = tan(fmin(rho, 1.5)) * (rho > 1.5 ? 3.0 + 20.0 * (rho - 1.5) : 1.0);
        for (int i = 0; i < n; ++i) { /* counter-clockwise about c */
            double ph = ph0 + 2.0 * MF_PI * i / n;
            mf_vec3 p = mf_vec3_add(c, mf_vec3_add(mf_vec3_scale(t1, tr * cos(ph)), mf_vec3_scale(t2, tr * sin(ph))));
            if (k % 5 == 1)
                p = mf_vec3_normalize(p);
            v[0] = p.x, v[1] = p.y, v[2] = p.z;
            v += 3;
        }
        nv[k] = n;
    }
    return NL;
}

static void check_case(const char *name, const double *dirs, int n, mf_vec3 axis, const int *nv, const double *verts,
                       long *inside_total)
{
    static uint64_t a[NMAX], b[NMAX];
    const double ax[3] = {axis.x, axis.y, axis.z};
    CHECK(mf_ltcfit_aniso_mask_compare(dirs, n, ax, NL, nv, verts, a, b) == 0);
    int bad = 0;
    long in = 0;
    for (int j = 0; j < n; ++j) {
        in += popcount64(b[j]);
        if (a[j] != b[j] && bad++ < 5)
            fprintf(stderr, "%s: direction %d (%.17g, %.17g, %.17g): cells %016llx direct %016llx\n", name, j,
                    dirs[3 * j], dirs[3 * j + 1], dirs[3 * j + 2], (unsigned long long)a[j], (unsigned long long)b[j]);
    }
    CHECKF(memcmp(a, b, sizeof *a * (size_t)n) == 0, "%s: %d of %d directions differ", name, bad, n);
    *inside_total += in;
}

int main(void)
{
    mf_pcg32 r;
    mf_pcg32_seed(&r, mf_test_seed(20261202), 3);
    static double dirs[3 * NMAX], verts[3 * 8 * NL];
    static int nv[NL];
    long inside = 0, edge_dirs = 0;
    for (int rep = 0; rep < 12; ++rep) {
        mf_vec3 axis = rep == 0 ? mf_vec3_make(0, 0, 1) : tilt(&r, mf_vec3_make(0, 0, 1), 1.4 * mf_pcg32_next_double(&r));
        double spread = 0.01 * pow(100.0, mf_pcg32_next_double(&r)); /* 0.01 .. 1 rad */
        make_lights(&r, axis, spread, nv, verts);
        int n = 0;
        /* a lobe of directions about the axis, a second cluster, a few anywhere */
        mf_vec3 second = tilt(&r, axis, 2.0 * spread);
        int nlobe = 3001 + 2000 * (rep % 3);
        for (int j = 0; j < nlobe; ++j) {
            mf_vec3 d = j % 7 == 0   ? rnd_unit(&r)
                        : j % 3 == 0 ? tilt(&r, second, 0.2 * spread * mf_pcg32_next_double(&r))
                                     : tilt(&r, axis, spread * -log(1.0 - 0.999 * mf_pcg32_next_double(&r)));
            dirs[3 * n] = d.x, dirs[3 * n + 1] = d.y, dirs[3 * n + 2] = d.z, ++n;
        }
        /* on every light's edges (vertices and midpoints, normalised) and its cap's rim, each also
         * with a few tiny clusters about it */
        const double *v = verts;
        for (int k = 0; k < NL; ++k) {
            mf_vec3 c = mf_vec3_make(0, 0, 0);
            for (int i = 0; i < nv[k]; ++i)
                c = mf_vec3_add(c, mf_vec3_normalize(mf_vec3_make(v[3 * i], v[3 * i + 1], v[3 * i + 2])));
            c = mf_vec3_normalize(c);
            for (int i = 0; i < nv[k]; ++i) {
                int i1 = (i + 1) % nv[k];
                mf_vec3 p = mf_vec3_normalize(mf_vec3_make(v[3 * i], v[3 * i + 1], v[3 * i + 2]));
                mf_vec3 q = mf_vec3_normalize(mf_vec3_make(v[3 * i1], v[3 * i1 + 1], v[3 * i1 + 2]));
                mf_vec3 pts[3] = {p, mf_vec3_normalize(mf_vec3_add(p, q)),
                                  mf_vec3_normalize(mf_vec3_add(mf_vec3_scale(p, 0.3), mf_vec3_scale(q, 0.7)))};
                for (int s = 0; s < 3; ++s)
                    for (int e = 0; e < 3 && n < NMAX - 8; ++e) {
                        mf_vec3 d = e == 0 ? pts[s] : tilt(&r, pts[s], 1e-13 * e);
                        dirs[3 * n] = d.x, dirs[3 * n + 1] = d.y, dirs[3 * n + 2] = d.z, ++n, ++edge_dirs;
                    }
            }
            v += 3 * nv[k];
        }
        /* behind the axis (the extra cell), and at -axis itself */
        for (int j = 0; j < 5 && n < NMAX; ++j) {
            mf_vec3 d = j == 0 ? mf_vec3_scale(axis, -1.0) : tilt(&r, mf_vec3_scale(axis, -1.0), 1e-4 * j);
            dirs[3 * n] = d.x, dirs[3 * n + 1] = d.y, dirs[3 * n + 2] = d.z, ++n;
        }
        if (rep == 5) /* non-unit directions: their cells prove nothing */
            for (int j = 0; j < n; j += 11)
                for (int q = 0; q < 3; ++q)
                    dirs[3 * j + q] *= 1.0 + 1e-6 * (j % 5);
        check_case("mixed", dirs, n | 1, axis, nv, verts, &inside); /* n odd: the scalar tail */
        check_case("mixed, even", dirs, n & ~1, axis, nv, verts, &inside);
        /* all directions identical (a zero spread), on a light's vertex */
        for (int j = 0; j < 257; ++j)
            memcpy(dirs + 3 * j, dirs + 3 * (nlobe + 1), 3 * sizeof(double));
        check_case("identical", dirs, 257, axis, nv, verts, &inside);
    }
    printf("directions on edges %ld, inside pairs %ld\n", edge_dirs, inside);
    CHECK(inside > 100000); /* the lights hold directions: the comparison is not of empty sets */
    MF_TEST_MAIN_END();
}
