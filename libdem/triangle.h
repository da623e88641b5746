/* Closest point of a triangle to a point, with the feature it lies on (Ericson, Real-Time
 * Collision Detection, 5.1.5): the region tests use the signs of the barycentric
 * sub-determinants, so a point exactly on an edge or vertex is classified as that edge or
 * vertex, never as the face. */
#ifndef DEM_TRIANGLE_H
#define DEM_TRIANGLE_H

enum {
    TRI_FACE = 0,
    TRI_EDGE_AB = 1, /* edge k (k = 0, 1, 2) is region 1 + k: ab, bc, ca */
    TRI_EDGE_BC = 2,
    TRI_EDGE_CA = 3,
    TRI_VERT_A = 4, /* vertex k is region 4 + k */
    TRI_VERT_B = 5,
    TRI_VERT_C = 6
};

static inline int tri_closest_point(const double *p, const double *a, const double *b, const double *c, double *q)
{
    double ab[3], ac[3], ap[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = p[k] - a[k];
    }
    const double d1 = ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2];
    const double d2 = ac[0] * ap[0] + ac[1] * ap[1] + ac[2] * ap[2];
    if (d1 <= 0.0 && d2 <= 0.0) {
        for (int k = 0; k < 3; k++) q[k] = a[k];
        return TRI_VERT_A;
    }
    double bp[3];
    for (int k = 0; k < 3; k++) bp[k] = p[k] - b[k];
    const double d3 = ab[0] * bp[0] + ab[1] * bp[1] + ab[2] * bp[2];
    const double d4 = ac[0] * bp[0] + ac[1] * bp[1] + ac[2] * bp[2];
    if (d3 >= 0.0 && d4 <= d3) {
        for (int k = 0; k < 3; k++) q[k] = b[k];
        return TRI_VERT_B;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        const double v = d1 / (d1 - d3);
        for (int k = 0; k < 3; k++) q[k] = a[k] + v * ab[k];
        return TRI_EDGE_AB;
    }
    double cp[3];
    for (int k = 0; k < 3; k++) cp[k] = p[k] - c[k];
    const double d5 = ab[0] * cp[0] + ab[1] * cp[1] + ab[2] * cp[2];
    const double d6 = ac[0] * cp[0] + ac[1] * cp[1] + ac[2] * cp[2];
    if (d6 >= 0.0 && d5 <= d6) {
        for (int k = 0; k < 3; k++) q[k] = c[k];
        return TRI_VERT_C;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        const double w = d2 / (d2 - d6);
        for (int k = 0; k < 3; k++) q[k] = a[k] + w * ac[k];
        return TRI_EDGE_CA;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int k = 0; k < 3; k++) q[k] = b[k] + w * (c[k] - b[k]);
        return TRI_EDGE_BC;
    }
    const double denom = 1.0 / (va + vb + vc);
    const double v = vb * denom, w = vc * denom;
    for (int k = 0; k < 3; k++) q[k] = a[k] + ab[k] * v + ac[k] * w;
    return TRI_FACE;
}

/* Signed height of p above the plane through a with unit normal n: no point of a triangle
 * in that plane is closer to p than its absolute value. */
static inline double tri_plane_height(const double *p, const double *a, const double *n)
{
    return (p[0] - a[0]) * n[0] + (p[1] - a[1]) * n[1] + (p[2] - a[2]) * n[2];
}

static inline double tri_dist2(const double *p, const double *q)
{
    const double u0 = p[0] - q[0], u1 = p[1] - q[1], u2 = p[2] - q[2];
    return u0 * u0 + u1 * u1 + u2 * u2;
}

#endif
