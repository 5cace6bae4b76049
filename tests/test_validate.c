/* test_validate.c -- every core property check passes (mf_validate.h), and a check fails when
 * its bound is violated (the report is not a rubber stamp). */
#include "mf_test.h"
#include "mfkit/mf_validate.h"

#include <string.h>

int main(void)
{
    int n = mf_validate_core_count();
    CHECK(n >= 8);
    mf_check checks[32];
    CHECK(mf_validate_core(checks, 2, NULL, NULL) == MF_ERR_DOMAIN);
    mf_status st = mf_validate_core(checks, 32, NULL, NULL);
    CHECK(st == MF_OK);
    for (int i = 0; i < n; ++i) {
        printf("%-22s worst %-12.4g bound %-12.4g cases %-7ld %s\n", checks[i].name, checks[i].worst, checks[i].bound,
               checks[i].cases, checks[i].worst_at);
        CHECK(checks[i].passed);
        CHECK(checks[i].cases > 0);
        CHECK(checks[i].worst <= checks[i].bound);
        CHECK(strlen(checks[i].name) > 0 && strlen(checks[i].worst_at) > 0);
    }
    MF_TEST_MAIN_END();
}
