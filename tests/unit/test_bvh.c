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
    float *box;                         /* 6 (2n - 1) */
} tree;

static void tree_free(tree *t)
{
    free(t->left);
    free(t->right);
    free(t->parent);
    free(t->order);
    free(t->box);
}

static void build(const float *boxes, int n, tree *t)
{
    t->n = n;
    t->left = calloc((size_t)n, sizeof(int));
    t->right = calloc((size_t)n, sizeof(int));
    t->parent = calloc((size_t)(2 * n), sizeof(int));
    t->order = calloc((size_t)n, sizeof(int));
    t->box = calloc((size_t)(6 * (2 * n - 1)), sizeof(float));
    keyed *k = calloc((size_t)n, sizeof *k);
    pd_v3 lo = v3(1e300, 1e300, 1e300), hi = v3(-1e300, -1e300, -1e300);
    for (int i = 0; i < n; i++) {
        const float *b = boxes + 6 * i;
        pd_v3 c = v3(0.5 * (b[0] + b[3]), 0.5 * (b[1] + b[4]), 0.5 * (b[2] + b[5]));
        lo = v3(pd_min(lo.x, c.x), pd_min(lo.y, c.y), pd_min(lo.z, c.z));
        hi = v3(pd_max(hi.x, c.x), pd_max(hi.y, c.y), pd_max(hi.z, c.z));
    }
    pd_v3 inv = v3(1 / pd_max(hi.x - lo.x, 1e-300), 1 / pd_max(hi.y - lo.y, 1e-300),
                   1 / pd_max(hi.z - lo.z, 1e-300));
    for (int i = 0; i < n; i++) {
        const float *b = boxes + 6 * i;
        k[i].code =
            bvh_morton(v3(0.5 * (b[0] + b[3]), 0.5 * (b[1] + b[4]), 0.5 * (b[2] + b[5])), lo, inv);
        k[i].index = i;
    }
    qsort(k, (size_t)n, sizeof *k, keyed_cmp);
    bvh_code *codes = calloc((size_t)n, sizeof *codes);
    for (int s = 0; s < n; s++) {
        codes[s] = k[s].code;
        t->order[s] = k[s].index;
        memcpy(t->box + 6 * (n - 1 + s), boxes + 6 * k[s].index, sizeof(float) * 6);
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

static int meet(const float *a, const float *b)
{
    return a[0] <= b[3] && b[0] <= a[3] && a[1] <= b[4] && b[1] <= a[4] && a[2] <= b[5] &&
           b[2] <= a[5];
}

/* Every query finds exactly the brute-force set; the tree covers each leaf once. The boxes are
 * given in double and stored as the engine stores them: floats rounded outwards. */
static void check_against_brute_force(const double *dboxes, int n)
{
    float *boxes = malloc(sizeof(float) * 6 * (size_t)n);
    int outward = 1;
    for (int i = 0; i < 6 * n; i++) {
        boxes[i] = i % 6 < 3 ? bvh_down(dboxes[i]) : bvh_up(dboxes[i]);
        outward &= i % 6 < 3 ? boxes[i] <= dboxes[i] : boxes[i] >= dboxes[i];
    }
    CHECK(outward);
    tree t;
    build(boxes, n, &t);
    int *out = calloc((size_t)n, sizeof(int)), *seen = calloc((size_t)n, sizeof(int));
    int bad_tree = 0, bad_query = 0;
    /* each internal node's box holds its children's */
    for (int i = 0; i < n - 1; i++)
        for (int c = 0; c < 2; c++) {
            const float *p = t.box + 6 * i, *q = t.box + 6 * (c ? t.right[i] : t.left[i]);
            for (int k = 0; k < 3; k++)
                bad_tree |= q[k] < p[k] || q[3 + k] > p[3 + k];
        }
    float all[6] = {-1e30f, -1e30f, -1e30f, 1e30f, 1e30f, 1e30f};
    int m = bvh_query(t.box, t.left, t.right, n, all, out, n);
    CHECK_EQ_INT(n, m);
    for (int i = 0; i < m && i < n; i++)
        seen[out[i]]++;
    for (int i = 0; i < n; i++)
        bad_tree |= seen[i] != 1;
    for (int i = 0; i < n; i++) {
        const float *q = boxes + 6 * i;
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
    free(boxes);
    tree_free(&t);
}

TEST(random_boxes_of_varied_size)
{
    int n = 2000;
    double *b = malloc(sizeof(double) * 6 * n);
    for (int i = 0; i < n; i++) {
        double c[3];
        rnd3(c);
        c[2] *= 0.3;
        double h = 0.001 * pow(100, rnd()); /* 1e-3..0.1 */
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

/*
 * The candidate test on float boxes never drops two bounding spheres that touch: spheres of
 * 1 mm to 10 cm, touching to 1e-12 of their radii in double, anywhere within 1 km of the origin
 * (where a float's ulp, 61 um, is most of a small sphere's radius). Also checks that spheres
 * apart by more than the test's slack are dropped, so the test is not simply always true.
 */
TEST(float_boxes_keep_touching_spheres)
{
    int kept = 0, dropped = 0, far_tested = 0, n = 20000;
    for (int i = 0; i < n; i++) {
        double scale = pow(10, 3 * rnd()); /* 1 m .. 1 km from the origin */
        double draw[3];
        rnd3(draw);
        pd_v3 ca =
            v3(scale * (2 * draw[0] - 1), scale * (2 * draw[1] - 1), scale * (2 * draw[2] - 1));
        double ra = 1e-3 * pow(100, rnd()), rb = 1e-3 * pow(100, rnd());
        double u[3];
        do {
            for (int k = 0; k < 3; k++)
                u[k] = 2 * rnd() - 1;
        } while (u[0] * u[0] + u[1] * u[1] + u[2] * u[2] < 0.01 ||
                 u[0] * u[0] + u[1] * u[1] + u[2] * u[2] > 1);
        double len = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        double d = (ra + rb) * (1 - 1e-12);
        pd_v3 cb = v3(ca.x + d * u[0] / len, ca.y + d * u[1] / len, ca.z + d * u[2] / len);
        float a[6], b[6];
        bvh_cube(ca, ra, a);
        bvh_cube(cb, rb, b);
        kept += bvh_boxes_meet_priv(a, b) && bvh_spheres_meet_priv(a, b);
        /* twice as far: the slack (a few ulps of the coordinates) is far below ra + rb there
         * only when the spheres are not tiny against the coordinates' ulp */
        double far = 2 * (ra + rb);
        if (far > 1e4 * FLT_EPSILON * scale) {
            pd_v3 cc =
                v3(ca.x + far * u[0] / len, ca.y + far * u[1] / len, ca.z + far * u[2] / len);
            bvh_cube(cc, rb, b);
            dropped += !(bvh_boxes_meet_priv(a, b) && bvh_spheres_meet_priv(a, b));
            far_tested++;
        }
    }
    CHECK_EQ_INT(n, kept);
    CHECK_EQ_INT(far_tested, dropped);
    CHECK(far_tested > n / 2);
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
    RUN(float_boxes_keep_touching_spheres);
    RUN(morton_code_orders_by_octant);
    return TEST_DONE();
}
