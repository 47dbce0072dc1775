/*
 * loadid_pipeline_why_not: the words for each reason a group is not
 * identified (docs/INTERFACE.md, the JSON's not_identified), written
 * from the interface's table.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "loadid/load_model.h"
#include "loadid/pipeline.h"

static loadid_pipeline_estimate_t final_estimate(int group, int why, double over) {
    loadid_pipeline_estimate_t e;
    memset(&e, 0, sizeof e);
    e.valid = e.has_model = 1;
    e.identified = (LOADID_IDENT_MASS | LOADID_IDENT_COM | LOADID_IDENT_INERTIA) & ~(1 << group);
    e.ident_why[group] = why;
    e.ident_over[group] = over;
    return e;
}

static void test_each_reason_in_words(void **state) {
    (void)state;
    const struct {
        int group, why;
        double over;
        const char *text;
    } cases[] = {
        {0, LOADID_WHY_STD, 19.5, "phi_std 19.5 times its bound"},
        /* Just past the bound: never "1 times". */
        {2, LOADID_WHY_STD, 1.0004, "phi_std 1.0004 times its bound"},
        {2, LOADID_WHY_GYRATION, 1.003, "radius of gyration 1.003 times its bound"},
        {2, LOADID_WHY_STD, INFINITY, "phi_std infinite: the data do not bound it"},
        {2, LOADID_WHY_STD, NAN, "phi_std not a number: its covariance failed"},
        {1, LOADID_WHY_NEEDS, 0, "needs the mass"},
        {2, LOADID_WHY_NEEDS, 0, "needs the com"},
        {2, LOADID_WHY_GYRATION, 24.5, "radius of gyration 24.5 times its bound"},
        {2, LOADID_WHY_SNR, 1.0 / 0.9,
         "its torque stands out of the noise 1.11 times less than the bound, as on slow or "
         "mostly translational motion"},
        {2, LOADID_WHY_SNR, INFINITY, "its torque does not stand out of the noise at all"},
        {0, LOADID_WHY_NO_MASS, 0, "no positive mass"},
        {0, LOADID_WHY_JOINT_NOISE, 67.6,
         "the joint positions are 67.6 times noisier than kalman.meas_sigma: phi_std does not "
         "count what the joint filters passed on"},
        {1, LOADID_WHY_JOINT_STAMPS, 19,
         "the joint stamps lost the stream's rate 19 times in the window: phi_std does not "
         "count the joint states taken at wrong times"},
    };
    char out[160];
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        const loadid_pipeline_estimate_t e =
            final_estimate(cases[i].group, cases[i].why, cases[i].over);
        assert_int_equal(loadid_pipeline_why_not(&e, cases[i].group, out, sizeof out), 1);
        assert_string_equal(out, cases[i].text);
        /* The other groups are identified: nothing to say. */
        const int other = (cases[i].group + 1) % 3;
        assert_int_equal(loadid_pipeline_why_not(&e, other, out, sizeof out), 0);
        assert_string_equal(out, "");
    }
}

static void test_no_estimate_and_no_model(void **state) {
    (void)state;
    char out[32] = "x";
    loadid_pipeline_estimate_t e;
    memset(&e, 0, sizeof e);
    /* No estimate (its error says why): every group says so. */
    for (int g = 0; g < 3; ++g) {
        assert_int_equal(loadid_pipeline_why_not(&e, g, out, sizeof out), 1);
        assert_string_equal(out, "no estimate");
    }
    /* A per-sample estimate has no load model: nothing. */
    e.valid = 1;
    e.ident_why[0] = LOADID_WHY_STD;
    assert_int_equal(loadid_pipeline_why_not(&e, 0, out, sizeof out), 0);
    assert_string_equal(out, "");
    /* A short buffer is cut, never overrun; bad arguments say nothing. */
    e = final_estimate(0, LOADID_WHY_STD, 19.5);
    char tiny[8];
    assert_int_equal(loadid_pipeline_why_not(&e, 0, tiny, sizeof tiny), 1);
    assert_string_equal(tiny, "phi_std");
    assert_int_equal(loadid_pipeline_why_not(&e, 3, out, sizeof out), 0);
    assert_int_equal(loadid_pipeline_why_not(NULL, 0, out, sizeof out), 0);
    assert_int_equal(loadid_pipeline_why_not(&e, 0, out, 0), 0);
    assert_int_equal(loadid_pipeline_why_not(&e, 0, NULL, sizeof out), 0);
    /* A restored result keeps the groups, not the reasons. */
    memset(&e, 0, sizeof e);
    e.valid = e.has_model = 1;
    e.identified = LOADID_IDENT_MASS;
    assert_int_equal(loadid_pipeline_why_not(&e, 0, out, sizeof out), 0);
    assert_int_equal(loadid_pipeline_why_not(&e, 1, out, sizeof out), 1);
    assert_string_equal(out, "not identified (no reason kept)");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_each_reason_in_words),
        cmocka_unit_test(test_no_estimate_and_no_model),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
