/* test_table_kind.c -- the registry of table kinds (mf_table_kind.h): every registered kind is
 * complete and recognised from its layout and from its "kind" metadata; each kind's gate passes
 * a table with the exact answer and fails the corrupted copies; moment maps convert to tables
 * and back bit for bit. */
#include "mf_test.h"
#include "test_tables.h"

#include "mfkit/mfkit.h"

#include <string.h>

/* Every registered kind: named, described, axes and fields declared, a gate with checks. */
static void test_registry(void)
{
    int n = mf_table_kind_count();
    CHECK(n == 7); /* ltc_isotropic, ggx_proxy, moment_map, dfg, kulla_conty, dielectric, ltc_anisotropic */
    CHECK(mf_table_kind_at(-1) == NULL && mf_table_kind_at(n) == NULL);
    CHECK(mf_table_kind_find("no_such_kind") == NULL && mf_table_kind_find(NULL) == NULL);
    for (int i = 0; i < n; ++i) {
        const mf_table_kind *k = mf_table_kind_at(i);
        printf("kind %-14s %d axes, %d fields, %d checks: %s\n", k->name, k->naxes, k->nfields, k->nchecks,
               k->description);
        CHECK(k->name && k->name[0] && k->description && k->description[0]);
        CHECK(mf_table_kind_find(k->name) == k);
        CHECK(k->naxes >= 1 && k->naxes <= MF_TABLE_MAX_AXES && k->axes != NULL);
        CHECK(k->nfields >= 1 && k->fields != NULL && k->required_fields >= 1 && k->required_fields <= k->nfields);
        CHECK(k->layout_ok && k->gate && k->checks && k->nchecks >= 1);
        for (int c = 0; c < k->nchecks; ++c)
            CHECK(k->checks[c].name && k->checks[c].run && k->checks[c].bound >= 0.0);
        for (int j = 0; j < i; ++j)
            CHECK(strcmp(mf_table_kind_at(j)->name, k->name) != 0);
    }
}

/* The isotropic LTC table: detected from its layout (the default tables carry no "kind" key, so
 * their bytes do not change), its declared axes are those mf_ltc_table_create makes, and the
 * kind's gate is the LTC gate. */
static void test_ltc(void)
{
    const mf_table_kind *k = mf_table_kind_find("ltc_isotropic");
    CHECK(k != NULL);
    if (!k)
        return;
    mf_table t;
    CHECK(mf_ltc_table_create(&t, 16, 16) == MF_OK);
    for (size_t i = 0; i < mf_table_texels(&t); ++i) {
        double *r = t.data + i * (size_t)t.nfields;
        r[MF_LTC_F_MINV_00] = r[MF_LTC_F_MINV_22] = r[MF_LTC_F_MAGNITUDE] = 1.0; /* Lambert: the identity */
    }
    char why[160];
    CHECK(mf_table_get_meta(&t, "kind") == NULL);
    CHECK(mf_table_kind_of(&t, why, sizeof why) == k);
    for (int a = 0; a < 2; ++a) {
        CHECK(!strcmp(t.axes[a].name, k->axes[a].name) && !strcmp(t.axes[a].physical, k->axes[a].physical));
        CHECK(t.axes[a].mapping == k->axes[a].mapping && t.axes[a].physical_min == k->axes[a].physical_min);
        CHECK(t.axes[a].lo == k->axes[a].lo && t.axes[a].hi == k->axes[a].hi);
    }
    CHECK(k->nfields == MF_LTC_NFIELDS && !strcmp(k->fields[MF_LTC_F_MAGNITUDE], "magnitude"));
    int nd = 0;
    CHECK(k->checks == mf_ltc_gate_checks(&nd) && k->nchecks == nd);
    mf_check a[MF_LTC_GATE_MAX_CHECKS], b[MF_LTC_GATE_MAX_CHECKS];
    int na = 0, nb = 0;
    CHECK(mf_table_kind_gate(&t, NULL, NULL, a, MF_LTC_GATE_MAX_CHECKS, &na) == MF_OK);
    CHECK(mf_ltc_gate_run(&t, NULL, NULL, b, MF_LTC_GATE_MAX_CHECKS, &nb) == MF_OK);
    CHECK(na == 5 && na == nb && !memcmp(a, b, sizeof a[0] * (size_t)na));
    /* tagged: found from the metadata; a tag that contradicts the layout is refused with a reason */
    CHECK(mf_table_kind_tag(&t, k) == MF_OK && !strcmp(mf_table_get_meta(&t, "kind"), "ltc_isotropic"));
    CHECK(mf_table_kind_of(&t, why, sizeof why) == k);
    CHECK(mf_table_set_meta(&t, "kind", "moment_map") == MF_OK);
    CHECK(mf_table_kind_of(&t, why, sizeof why) == NULL);
    printf("contradicting tag: %s\n", why);
    CHECK(strstr(why, "moment_map") && strstr(why, "axis 0"));
    CHECK(mf_table_set_meta(&t, "kind", "no_such_kind") == MF_OK);
    CHECK(mf_table_kind_of(&t, why, sizeof why) == NULL && strstr(why, "unknown kind"));
    mf_table_free(&t);
}

/* The GGX proxy table as `mfkit fit ggx-proxy` writes it (16 x 16 here), by the same functions. */
static int proxy_table(mf_table *t)
{
    const mf_table_kind *k = mf_table_kind_find("ggx_proxy");
    mf_table_axis ax[2];
    memset(ax, 0, sizeof ax);
    for (int a = 0; a < 2; ++a) {
        snprintf(ax[a].name, sizeof ax[a].name, "%s", k->axes[a].name);
        snprintf(ax[a].physical, sizeof ax[a].physical, "%s", k->axes[a].physical);
        ax[a].size = 16;
        ax[a].lo = k->axes[a].lo;
        ax[a].hi = k->axes[a].hi;
        ax[a].mapping = k->axes[a].mapping;
        ax[a].physical_min = k->axes[a].physical_min;
    }
    if (mf_table_create(t, 2, ax, k->nfields, k->fields) != MF_OK)
        return 0;
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i) {
            double a = pow(10.0, mf_table_axis_param(&ax[0], i)), d = pow(10.0, mf_table_axis_param(&ax[1], j));
            double *r = t->data + (size_t)(i + 16 * j) * 5;
            r[0] = a;
            r[1] = d;
            r[2] = mf_filter_ggx_proxy_alpha(a, d);
            r[3] = mf_filter_ggx_proxy_alpha_approx(a, d);
            r[4] = mf_proxy_alpha_fit(a, d);
        }
    return 1;
}

/* Runs the gate of t's kind; exactly the checks in must_fail fail. */
static void expect(const char *title, const mf_table *t, const char *kind, const char *const *must_fail, int nfail)
{
    mf_check c[8];
    int n = 0;
    mf_status st = mf_table_kind_gate(t, NULL, NULL, c, 8, &n);
    mf_test_print_checks(title, c, n);
    const mf_table_kind *k = mf_table_kind_of(t, NULL, 0);
    CHECK(k && !strcmp(k->name, kind));
    CHECK(k && n == k->nchecks);
    CHECK(st == (nfail ? MF_ERR_CHECK_FAILED : MF_OK));
    for (int i = 0; i < n; ++i) {
        int should_fail = 0;
        for (int f = 0; f < nfail; ++f)
            should_fail |= !strcmp(c[i].name, must_fail[f]);
        if (c[i].passed == should_fail)
            MF_FAIL_AT("%s: check %s %s", title, c[i].name, c[i].passed ? "passed but must fail" : "failed");
    }
}

static void test_proxy(void)
{
    mf_table t;
    CHECK(proxy_table(&t));
    if (!t.data)
        return;
    expect("proxy: exact table", &t, "ggx_proxy", NULL, 0);
    /* alpha_eff 1e-10 off (100 x the bound) at one texel */
    mf_table bad;
    CHECK(mf_table_copy(&bad, &t) == MF_OK);
    bad.data[(3 + 16 * 7) * 5 + 2] *= 1.0 + 1e-10;
    {
        const char *const f[] = {"proxy_exact"};
        expect("proxy: alpha_eff off by 1e-10", &bad, "ggx_proxy", f, 1);
    }
    mf_table_free(&bad);
    /* the fitted form 1e-5 off (3 x the bound) */
    CHECK(mf_table_copy(&bad, &t) == MF_OK);
    bad.data[(9 + 16 * 2) * 5 + 4] *= 1.0 + 1e-5;
    {
        const char *const f[] = {"proxy_fit"};
        expect("proxy: fit off by 1e-5", &bad, "ggx_proxy", f, 1);
    }
    mf_table_free(&bad);
    /* a NaN: counted by proxy_finite, and a NaN case (worst NaN, "NaN at") of the other two */
    CHECK(mf_table_copy(&bad, &t) == MF_OK);
    bad.data[(5 + 16 * 5) * 5 + 2] = NAN;
    {
        const char *const f[] = {"proxy_finite", "proxy_exact", "proxy_fit"};
        expect("proxy: a NaN", &bad, "ggx_proxy", f, 3);
        mf_check c[8];
        int n = 0;
        CHECK(mf_table_kind_gate(&bad, NULL, NULL, c, 8, &n) == MF_ERR_CHECK_FAILED);
        const mf_check *e = mf_test_find_check(c, n, "proxy_exact");
        CHECK(e && isnan(e->worst) && strstr(e->worst_at, "NaN at texel 85") == e->worst_at);
    }
    mf_table_free(&bad);
    /* too small an output array */
    mf_check c[2];
    int n = -1;
    CHECK(mf_table_kind_gate(&t, NULL, NULL, c, 2, &n) == MF_ERR_DOMAIN && n == 0);
    mf_table_free(&t);
}

/* A moments MIP chain of a sine height field (odd sizes: the box filter's partial texels) to
 * tables and back. */
static void test_moment_maps(void)
{
    const int w = 37, h = 20;
    mf_map hm, sl, mo;
    CHECK(mf_map_alloc(&hm, w, h, 1) == MF_OK);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i)
            hm.data[j * w + i] = 0.3 * sin(0.9 * i + 0.2) * cos(0.7 * j) + 0.05 * i;
    CHECK(mf_map_slopes_from_heights(&hm, 0, 1.0, 1.0, MF_MAP_EDGE_WRAP, &sl, NULL) == MF_OK);
    CHECK(mf_map_moments_from_slopes(&sl, &mo) == MF_OK);
    int nl = mf_map_mip_count(w, h);
    mf_map levels[16];
    levels[0] = mo;
    for (int l = 1; l < nl; ++l)
        CHECK(mf_map_box_downsample(&levels[l - 1], &levels[l]) == MF_OK);
    mf_table tables[16];
    CHECK(mf_map_chain_to_tables(levels, nl, tables) == MF_OK);
    const mf_table_kind *k = mf_table_kind_find("moment_map");
    for (int l = 0; l < nl; ++l) {
        const mf_table *t = &tables[l];
        char title[64], lv[16];
        snprintf(title, sizeof title, "moment map level %d (%d x %d)", l, levels[l].width, levels[l].height);
        snprintf(lv, sizeof lv, "%d", l);
        CHECK(!strcmp(mf_table_get_meta(t, "kind"), "moment_map") && !strcmp(mf_table_get_meta(t, "level"), lv));
        CHECK(mf_table_kind_of(t, NULL, 0) == k);
        CHECK(t->axes[0].size == levels[l].width && t->axes[1].size == levels[l].height);
        expect(title, t, "moment_map", NULL, 0);
        /* texel (i, j) of the map is the record (i, j) of the table, at tex (u, v) = ((i+.5)/w, 1-(j+.5)/h) */
        int i = levels[l].width / 2, j = levels[l].height - 1;
        int idx[2] = {i, j};
        CHECK(mf_table_record(t, idx)[MF_MAP_M_XY] == levels[l].data[((size_t)j * levels[l].width + i) * 5 + MF_MAP_M_XY]);
        /* absolute 2.3e-16 (one ulp of 1): both sides round a difference of numbers <= 1 */
        CHECK_ABS(mf_table_axis_param(&t->axes[1], j), 1.0 - (j + 0.5) / levels[l].height, 2.3e-16);
        mf_map back;
        CHECK(mf_map_moments_from_table(t, &back) == MF_OK);
        CHECK(back.width == levels[l].width && back.height == levels[l].height &&
              !memcmp(back.data, levels[l].data, sizeof(double) * 5 * (size_t)back.width * (size_t)back.height));
        mf_map_free(&back);
    }
    /* a texel whose variance is negative (E[x^2] < E[x]^2) fails moment_covariance */
    mf_table bad;
    CHECK(mf_table_copy(&bad, &tables[1]) == MF_OK);
    double *r = bad.data + 7 * 5;
    r[MF_MAP_M_XX] = r[MF_MAP_MEAN_X] * r[MF_MAP_MEAN_X] * (1.0 - 1e-6) - 1e-9;
    {
        const char *const f[] = {"moment_covariance"};
        expect("moment map: negative variance", &bad, "moment_map", f, 1);
    }
    mf_table_free(&bad);
    /* not a moments map */
    mf_map three;
    CHECK(mf_map_alloc(&three, 4, 4, 3) == MF_OK);
    mf_table t3;
    CHECK(mf_map_moments_to_table(&three, 0, &t3) == MF_ERR_DOMAIN && t3.data == NULL);
    mf_map_free(&three);
    for (int l = 0; l < nl; ++l) {
        mf_table_free(&tables[l]);
        mf_map_free(&levels[l]);
    }
    mf_map_free(&hm);
    mf_map_free(&sl);
}

/* A table of no registered kind: NULL with the reason. */
static void test_unknown(void)
{
    mf_table_axis ax[3];
    memset(ax, 0, sizeof ax);
    for (int a = 0; a < 3; ++a) {
        snprintf(ax[a].name, sizeof ax[a].name, "x%d", a);
        snprintf(ax[a].physical, sizeof ax[a].physical, "x%d", a);
        ax[a].size = 3;
        ax[a].hi = 1.0;
        ax[a].physical_min = -INFINITY;
    }
    const char *f[1] = {"v"};
    mf_table t;
    CHECK(mf_table_create(&t, 3, ax, 1, f) == MF_OK);
    char why[160];
    CHECK(mf_table_kind_of(&t, why, sizeof why) == NULL);
    printf("unknown: %s\n", why);
    CHECK(strstr(why, "matches no registered kind") != NULL);
    mf_check c[8];
    int n = -1;
    CHECK(mf_table_kind_gate(&t, NULL, NULL, c, 8, &n) == MF_ERR_DOMAIN && n == 0);
    mf_table_free(&t);
}

int main(void)
{
    test_registry();
    test_ltc();
    test_proxy();
    test_moment_maps();
    test_unknown();
    MF_TEST_MAIN_END();
}
