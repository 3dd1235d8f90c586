/*
 * test_contact_history.c - contact keys, history carried by key, and the deterministic gather of
 * kernels/contact_history.h.
 */
#define PD_DOUBLE 1
#include <string.h>

#include "contact_history.h"
#include "test.h"
#define TEST_RANDOM_SEED 3
#include "test_random.h"

static int key_cmp(const void *a, const void *b)
{
    ch_key x = *(const ch_key *)a, y = *(const ch_key *)b;
    return x < y ? -1 : x > y;
}

TEST(keys_and_lookup)
{
    CHECK(ch_make(3, 7) < ch_make(3, 8));
    CHECK(ch_make(3, CH_WALL + 1) > ch_make(3, 9999)); /* walls after particles */
    CHECK(ch_make(2, 0xffffffffu) < ch_make(3, 0));
    CHECK_EQ_INT(3, ch_first(ch_make(3, 7)));
    CHECK_EQ_INT(7, ch_second(ch_make(3, 7)));
    ch_key k[6] = {ch_make(0, 1),       ch_make(0, 5), ch_make(2, 3),
                   ch_make(2, CH_WALL), ch_make(4, 9), ch_make(7, 8)};
    for (int i = 0; i < 6; i++)
        CHECK_EQ_INT(i, ch_find(k, 6, k[i]));
    CHECK_EQ_INT(-1, ch_find(k, 6, ch_make(2, 4)));
    CHECK_EQ_INT(-1, ch_find(k, 6, ch_make(9, 0)));
    CHECK_EQ_INT(-1, ch_find(k, 0, ch_make(0, 1)));
    CHECK_EQ_INT(2, ch_lower_bound(k, 6, ch_make(2, 0)));
}

TEST(history_follows_the_pair_not_the_slot)
{
    /* the last list's pairs that carried state, by first body (particles 0..3: 0 has two, 1 one,
     * 2 and 3 none); this step: one ended, one new, order changed */
    ch_key carry_k[3] = {ch_make(0, 1), ch_make(0, 2), ch_make(1, 2)};
    int carry_off[5] = {0, 2, 3, 3, 3};
    ch_key new_k[4] = {ch_make(0, 2), ch_make(1, 2), ch_make(1, 3), ch_make(2, 3)};
    int want[4] = {1, 2, -1, -1};
    for (int i = 0; i < 4; i++)
        CHECK_EQ_INT(want[i], ch_carried(carry_k, carry_off, new_k[i]));
    /* a key of another first body is not found in a segment it is not in */
    CHECK_EQ_INT(-1, ch_carried(carry_k, carry_off, ch_make(1, 0)));
}

TEST(gather_equals_the_direct_sum_exactly)
{
    enum { NP = 50, NC = 400 };
    /* random distinct pairs, force components small integers: every sum is exact, so the
     * gather must equal the direct accumulation exactly */
    ch_key keys[NC];
    int n = 0;
    while (n < NC) {
        unsigned a = (unsigned)(rnd64() % NP), b = (unsigned)(rnd64() % NP);
        if (a >= b) continue;
        ch_key k = ch_make(a, b);
        int dup = 0;
        for (int i = 0; i < n; i++)
            dup |= keys[i] == k;
        if (!dup) keys[n++] = k;
    }
    qsort(keys, NC, sizeof keys[0], key_cmp);
    /* small integers everywhere: the cross products and sums are exact, so the gather must equal
     * the direct accumulation exactly */
    double force[3 * NC], point[3 * NC], moment[3 * NC], torque[3 * NC], x[3 * NP];
    for (int i = 0; i < 3 * NP; i++)
        x[i] = (double)(int)(rnd64() % 21) - 10;
    for (int i = 0; i < 3 * NC; i++) {
        force[i] = (double)(int)(rnd64() % 201) - 100;
        point[i] = (double)(int)(rnd64() % 21) - 10;
        moment[i] = (double)(int)(rnd64() % 41) - 20;
    }
    /* what the contact stage stores: the first body's torque, not the point and the moment */
    for (int c = 0; c < NC; c++)
        v3_store(torque, c,
                 ch_first_torque(v3_load(x, (int)ch_first(keys[c])), v3_load(point, c),
                                 v3_load(force, c), v3_load(moment, c)));
    /* first-body segments from the sorted keys; second-body lists in reverse contact order, so
     * the gather must sort them to sum in key order */
    int first[NP + 1] = {0}, second_off[NP + 1] = {0}, second_list[NC], fill[NP] = {0};
    for (int c = 0; c < NC; c++) {
        first[ch_first(keys[c]) + 1]++;
        second_off[ch_second(keys[c]) + 1]++;
    }
    for (int p = 0; p < NP; p++) {
        first[p + 1] += first[p];
        second_off[p + 1] += second_off[p];
    }
    for (int c = NC - 1; c >= 0; c--) {
        unsigned b = ch_second(keys[c]);
        second_list[second_off[b] + fill[b]++] = c;
    }
    double direct_f[3 * NP] = {0}, direct_t[3 * NP] = {0};
    for (int c = 0; c < NC; c++) {
        unsigned a = ch_first(keys[c]), b = ch_second(keys[c]);
        for (int k = 0; k < 3; k++) {
            direct_f[3 * a + k] -= force[3 * c + k];
            direct_f[3 * b + k] += force[3 * c + k];
            /* torque (point - x) x force: on b with +force and +moment, on a with both negated */
            int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            double fa1 = -force[3 * c + k1], fa2 = -force[3 * c + k2];
            double ra1 = point[3 * c + k1] - x[3 * a + k1], ra2 = point[3 * c + k2] - x[3 * a + k2];
            double rb1 = point[3 * c + k1] - x[3 * b + k1], rb2 = point[3 * c + k2] - x[3 * b + k2];
            direct_t[3 * a + k] += ra1 * fa2 - ra2 * fa1 - moment[3 * c + k];
            direct_t[3 * b + k] +=
                rb1 * force[3 * c + k2] - rb2 * force[3 * c + k1] + moment[3 * c + k];
        }
    }
    int exact = 1;
    for (unsigned p = 0; p < NP; p++) {
        pd_v3 f, t;
        ch_gather(p, first, second_off, second_list, keys, force, torque, x, &f, &t);
        exact &= f.x == direct_f[3 * p] && f.y == direct_f[3 * p + 1] &&
                 f.z == direct_f[3 * p + 2] && t.x == direct_t[3 * p] &&
                 t.y == direct_t[3 * p + 1] && t.z == direct_t[3 * p + 2];
    }
    CHECK(exact);
    int sorted = 1;
    for (int p = 0; p < NP; p++)
        for (int k = second_off[p] + 1; k < second_off[p + 1]; k++)
            sorted &= second_list[k - 1] < second_list[k];
    CHECK(sorted);
}

int main(void)
{
    RUN(keys_and_lookup);
    RUN(history_follows_the_pair_not_the_slot);
    RUN(gather_equals_the_direct_sum_exactly);
    return TEST_DONE();
}
