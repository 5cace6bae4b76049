/* A program outside the mfkit tree that uses the installed library. */
#include <mfkit/mfkit.h>
#include <stdio.h>

int main(void)
{
    mf_ndf ndf = mf_ndf_make(MF_NDF_GGX, 0.5, 0.5);
    double d = mf_ndf_d(ndf, mf_vec3_make(0.0, 0.0, 1.0));
    double expect = 1.0 / (MF_PI * 0.25);
    if (!(fabs(d - expect) <= 1e-15 * expect)) {
        fprintf(stderr, "consumer: D = %.17g, expected %.17g\n", d, expect);
        return 1;
    }
    printf("consumer: ok (%s)\n", mf_status_str(MF_OK));
    return 0;
}
