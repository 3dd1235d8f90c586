/*
 * test_contact_history.c - contact keys, history carried by key, and the deterministic gather of
 * kernels/contact_history.h.
 */
#define PD_DOUBLE 1
#include <string.h>

#include "contact_history.h"
#include "test.h"

static uint64_t rs = 3;
static uint64_t rnd64(void)
{
    uint64_t z = (rs += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

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
    /* last step: three contacts with springs; this step: one ended, one new, order changed */
    ch_key old_k[3] = {ch_make(0, 1), ch_make(0, 2), ch_make(1, 2)};
    double old_s[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9}, old_kt[3] = {10, 20, 30};
    ch_key new_k[3] = {ch_make(0, 2), ch_make(1, 2), ch_make(1, 3)};
    double s[9], kt[3];
    for (int i = 0; i < 3; i++)
        ch_carry(old_k, 3, old_s, old_kt, new_k[i], s, kt, i);
    CHECK_NEAR(4, s[0], 0);
    CHECK_NEAR(20, kt[0], 0);
    CHECK_NEAR(9, s[5], 0);
    CHECK_NEAR(30, kt[1], 0);
    CHECK_NEAR(0, s[6] + s[7] + s[8] + kt[2], 0); /* a new contact starts unloaded */
}

/* Builds the swapped-key index of sorted keys (by_second, swapped). */
typedef struct {
    ch_key k;
    int c;
} swap_entry;
static int swap_cmp(const void *a, const void *b)
{
    const swap_entry *x = a, *y = b;
    return x->k < y->k ? -1 : x->k > y->k;
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
    double force[3 * NC], tqa[3 * NC], tqb[3 * NC];
    for (int i = 0; i < 3 * NC; i++) {
        force[i] = (double)(int)(rnd64() % 201) - 100;
        tqa[i] = (double)(int)(rnd64() % 21) - 10;
        tqb[i] = (double)(int)(rnd64() % 21) - 10;
    }
    swap_entry sw[NC];
    for (int c = 0; c < NC; c++) {
        sw[c].k = ch_make(ch_second(keys[c]), ch_first(keys[c]));
        sw[c].c = c;
    }
    qsort(sw, NC, sizeof sw[0], swap_cmp);
    int by_second[NC];
    ch_key swapped[NC];
    for (int s = 0; s < NC; s++) {
        by_second[s] = sw[s].c;
        swapped[s] = sw[s].k;
    }
    double direct_f[3 * NP] = {0}, direct_t[3 * NP] = {0};
    for (int c = 0; c < NC; c++) {
        unsigned a = ch_first(keys[c]), b = ch_second(keys[c]);
        for (int k = 0; k < 3; k++) {
            direct_f[3 * a + k] -= force[3 * c + k];
            direct_f[3 * b + k] += force[3 * c + k];
            direct_t[3 * a + k] += tqa[3 * c + k];
            direct_t[3 * b + k] += tqb[3 * c + k];
        }
    }
    int exact = 1;
    for (unsigned p = 0; p < NP; p++) {
        pd_v3 f, t;
        ch_gather(p, keys, by_second, swapped, NC, force, tqa, tqb, &f, &t);
        exact &= f.x == direct_f[3 * p] && f.y == direct_f[3 * p + 1] &&
                 f.z == direct_f[3 * p + 2] && t.x == direct_t[3 * p] &&
                 t.y == direct_t[3 * p + 1] && t.z == direct_t[3 * p + 2];
    }
    CHECK(exact);
}

int main(void)
{
    RUN(keys_and_lookup);
    RUN(history_follows_the_pair_not_the_slot);
    RUN(gather_equals_the_direct_sum_exactly);
    return TEST_DONE();
}
