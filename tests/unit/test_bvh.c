/*
 * test_bvh.c - the LBVH of kernels/bvh.h against brute force: random boxes whose sizes vary by
 * two orders of magnitude (particle sizes vary, thesis section 5.5), boxes sharing centres (equal
 * Morton codes), and the smallest trees. Refit runs as a device would: a node is finished by the
 * second of its children to arrive.
 */
#define PD_DOUBLE 1
#include <stdint.h>
#include <string.h>

#include "bvh.h"
#include "test.h"
#define TEST_RANDOM_SEED 42
#include "test_random.h"

typedef struct {
    bvh_code code;
    int index;
} keyed;

static int keyed_cmp(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->code != y->code) return x->code < y->code ? -1 : 1;
    return x->index - y->index;
}

typedef struct {
    int n;
    int *left, *right, *parent, *order; /* order[k]: original index of sorted leaf k */
    double *box;                        /* 6 (2n - 1) */
} tree;

static void tree_free(tree *t)
{
    free(t->left);
    free(t->right);
    free(t->parent);
    free(t->order);
    free(t->box);
}

static void build(const double *boxes, int n, tree *t)
{
    t->n = n;
    t->left = calloc((size_t)n, sizeof(int));
    t->right = calloc((size_t)n, sizeof(int));
    t->parent = calloc((size_t)(2 * n), sizeof(int));
    t->order = calloc((size_t)n, sizeof(int));
    t->box = calloc((size_t)(6 * (2 * n - 1)), sizeof(double));
    keyed *k = calloc((size_t)n, sizeof *k);
    pd_v3 lo = v3(1e300, 1e300, 1e300), hi = v3(-1e300, -1e300, -1e300);
    for (int i = 0; i < n; i++) {
        const double *b = boxes + 6 * i;
        pd_v3 c = v3(0.5 * (b[0] + b[3]), 0.5 * (b[1] + b[4]), 0.5 * (b[2] + b[5]));
        lo = v3(pd_min(lo.x, c.x), pd_min(lo.y, c.y), pd_min(lo.z, c.z));
        hi = v3(pd_max(hi.x, c.x), pd_max(hi.y, c.y), pd_max(hi.z, c.z));
    }
    pd_v3 inv = v3(1 / pd_max(hi.x - lo.x, 1e-300), 1 / pd_max(hi.y - lo.y, 1e-300),
                   1 / pd_max(hi.z - lo.z, 1e-300));
    for (int i = 0; i < n; i++) {
        const double *b = boxes + 6 * i;
        k[i].code =
            bvh_morton(v3(0.5 * (b[0] + b[3]), 0.5 * (b[1] + b[4]), 0.5 * (b[2] + b[5])), lo, inv);
        k[i].index = i;
    }
    qsort(k, (size_t)n, sizeof *k, keyed_cmp);
    bvh_code *codes = calloc((size_t)n, sizeof *codes);
    for (int s = 0; s < n; s++) {
        codes[s] = k[s].code;
        t->order[s] = k[s].index;
        memcpy(t->box + 6 * (n - 1 + s), boxes + 6 * k[s].index, sizeof(double) * 6);
    }
    for (int i = 0; i < n - 1; i++)
        bvh_build_node(codes, n, i, t->left, t->right, t->parent);
    /* refit: from every leaf upwards; the second child to arrive finishes its parent */
    int *arrivals = calloc((size_t)n, sizeof(int));
    for (int s = 0; s < n && n > 1; s++) {
        int node = n - 1 + s;
        while (node != 0) {
            int p = t->parent[node];
            if (arrivals[p]++ == 0) break;
            bvh_node_box(t->box, t->left, t->right, p);
            node = p;
        }
    }
    free(arrivals);
    free(codes);
    free(k);
}

static int meet(const double *a, const double *b)
{
    return a[0] <= b[3] && b[0] <= a[3] && a[1] <= b[4] && b[1] <= a[4] && a[2] <= b[5] &&
           b[2] <= a[5];
}

/* Every query finds exactly the brute-force set; the tree covers each leaf once. */
static void check_against_brute_force(const double *boxes, int n)
{
    tree t;
    build(boxes, n, &t);
    int *out = calloc((size_t)n, sizeof(int)), *seen = calloc((size_t)n, sizeof(int));
    int bad_tree = 0, bad_query = 0;
    /* each internal node's box holds its children's */
    for (int i = 0; i < n - 1; i++)
        for (int c = 0; c < 2; c++) {
            const double *p = t.box + 6 * i, *q = t.box + 6 * (c ? t.right[i] : t.left[i]);
            for (int k = 0; k < 3; k++)
                bad_tree |= q[k] < p[k] || q[3 + k] > p[3 + k];
        }
    double all[6] = {-1e300, -1e300, -1e300, 1e300, 1e300, 1e300};
    int m = bvh_query(t.box, t.left, t.right, n, all, out, n);
    CHECK_EQ_INT(n, m);
    for (int i = 0; i < m && i < n; i++)
        seen[out[i]]++;
    for (int i = 0; i < n; i++)
        bad_tree |= seen[i] != 1;
    for (int i = 0; i < n; i++) {
        const double *q = boxes + 6 * i;
        int got = bvh_query(t.box, t.left, t.right, n, q, out, n), want = 0;
        for (int j = 0; j < n; j++)
            want += meet(q, boxes + 6 * j);
        if (got != want) {
            bad_query = 1;
            continue;
        }
        for (int s = 0; s < got; s++)
            bad_query |= !meet(q, boxes + 6 * t.order[out[s]]);
    }
    CHECK(!bad_tree);
    CHECK(!bad_query);
    free(out);
    free(seen);
    tree_free(&t);
}

TEST(random_boxes_of_varied_size)
{
    int n = 2000;
    double *b = malloc(sizeof(double) * 6 * n);
    for (int i = 0; i < n; i++) {
        double c[3] = {rnd(), rnd(), 0.3 * rnd()}, h = 0.001 * pow(100, rnd()); /* 1e-3..0.1 */
        for (int k = 0; k < 3; k++) {
            b[6 * i + k] = c[k] - h;
            b[6 * i + 3 + k] = c[k] + h;
        }
    }
    check_against_brute_force(b, n);
    free(b);
}

TEST(equal_centres_and_small_trees)
{
    /* 300 boxes on only 7 distinct centres: long runs of equal Morton codes */
    int n = 300;
    double *b = malloc(sizeof(double) * 6 * n);
    for (int i = 0; i < n; i++) {
        double c = (i % 7) * 0.1, h = 0.01 + 0.001 * (i % 5);
        for (int k = 0; k < 3; k++) {
            b[6 * i + k] = c - h;
            b[6 * i + 3 + k] = c + h;
        }
    }
    check_against_brute_force(b, n);
    for (int m = 1; m <= 5; m++)
        check_against_brute_force(b, m);
    free(b);
}

TEST(morton_code_orders_by_octant)
{
    /* the top three bits are x, y, z halves: (0.75, 0.25, 0.75) lies in octant 0b101 */
    pd_v3 lo = v3(0, 0, 0), inv = v3(1, 1, 1);
    bvh_code c = bvh_morton(v3(0.75, 0.25, 0.75), lo, inv);
    CHECK_EQ_INT(5, (int)(c >> 60));
    CHECK(bvh_morton(v3(1, 1, 1), lo, inv) == 0x7fffffffffffffffull);
    CHECK(bvh_morton(v3(-3, -3, -3), lo, inv) == 0); /* clamped into the scene box */
}

int main(void)
{
    RUN(random_boxes_of_varied_size);
    RUN(equal_centres_and_small_trees);
    RUN(morton_code_orders_by_octant);
    return TEST_DONE();
}
