/* test_ltcfit_cf_order.c -- the closed-form start of the anisotropic fits (mf_ltcfit_aniso.c,
 * closed_form_start) evaluated in its hinted order (the scale grid from the hint's
 * scale outwards, the aspect from the hint's ratio, the aspect's j = 0 skipped) against index order
 * (revision 7's loops), through mf_ltcfit_aniso_closed_form_compare.  The order promises the same
 * point and cost, so every comparison is exact (memcmp of the 7 parameters and of the cost): any
 * hint (including none), bounds that cut the aspect points (the cost itself, its neighbouring
 * doubles, half and twice of it, 0), with and without the warm solve's proximal terms, at views
 * from normal to grazing; and with every light's residual zero, where the grid's costs tie and
 * only the tie-break (the lowest index, as index order takes) decides. */
#include "mf_test.h"

#include "mfkit/fit/mf_ltcfit_aniso.h"
#include "mfkit/mfkit.h"

static void check_case(double ax, double ay, double theta, int mirrors, int flat, const double *prox)
{
    mf_brdf_params prm = {ax, ay};
    int mism = -1;
    int n = mf_ltcfit_aniso_closed_form_compare(mf_brdf_model_find("ggx"), prm, theta, mirrors, 0.9, 1024, flat, prox,
                                                &mism);
    printf("alpha (%.2f, %.2f) theta %.2f mirrors %d flat %d prox %s: %d comparisons, %d differ\n", ax, ay, theta,
           mirrors, flat, prox ? "on" : "off", n, mism);
    /* 7 bounds x 106 hints; exact (the order promises the same bits) */
    CHECK(n == 7 * 106);
    CHECK(mism == 0);
}

int main(void)
{
    const double warm[7] = {0.3, 0.0, 0.05, 0.12, 0.0, 0.0, 0.0};
    check_case(0.1, 0.1, 0.0, MF_LTCFIT_ANISO_MIRROR_Y | MF_LTCFIT_ANISO_MIRROR_X, 0, NULL);
    check_case(0.1, 0.1, 0.7, MF_LTCFIT_ANISO_MIRROR_Y, 0, NULL);
    check_case(0.3, 0.05, 1.0, 0, 0, warm);
    check_case(0.6, 0.6, 1.45, MF_LTCFIT_ANISO_MIRROR_Y, 0, warm);
    check_case(0.1, 0.1, 0.7, MF_LTCFIT_ANISO_MIRROR_Y, 1, NULL);
    /* bad arguments are refused */
    mf_brdf_params prm = {0.1, 0.1};
    int mism;
    CHECK(mf_ltcfit_aniso_closed_form_compare(NULL, prm, 0.5, 0, 0.9, 1024, 0, NULL, &mism) == -1);
    CHECK(mf_ltcfit_aniso_closed_form_compare(mf_brdf_model_find("ggx"), prm, 0.5, 0, 0.9, 1000, 0, NULL, &mism) == -1);
    MF_TEST_MAIN_END();
}
