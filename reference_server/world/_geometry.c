/* geometry.segments_clear's inner loops in C: the same tests and the same floating-point steps as the numpy
 * version in geometry.py (which stays the reference, the fallback and the tests' oracle).
 *
 * Rules:
 * - Only buffers of float64 / bool come in (the buffer protocol, no numpy headers); the caller passes C-contiguous
 *   arrays of those types and pre-fills ``ok`` with true; rad or ok shorter than the queries is a ValueError.
 * - A query stops at the first wall or circle it does not keep clear of: the answer is the same as numpy's
 *   "any over all", the work is not (the planner's visibility graph asks millions of pairs, most blocked early).
 * - np.minimum propagates NaN: nmin() does too, so a degenerate input gives numpy's answer.
 * - Built with -ffp-contract=off: no fused multiply-add, so each product rounds as numpy's does.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>

static double nmin(double a, double b) {
    if (a != a || b != b) return NAN;
    return a < b ? a : b;
}

/* _point_seg_d2: squared distance of (px, py) to the segment from (x0, y0) along (ex, ey), ll = |e|^2 */
static double d2(double px, double py, double x0, double y0, double ex, double ey, double ll) {
    double wx = px - x0, wy = py - y0;
    double t = ll > 0 ? (wx * ex + wy * ey) / ll : 0.0;
    if (t < 0.0)
        t = 0.0;
    else if (t > 1.0)
        t = 1.0;
    double dx = wx - t * ex, dy = wy - t * ey;
    return dx * dx + dy * dy;
}

/* PyBuffer_Release of each buffer of a NULL-terminated list: what every exit of the function does */
static void release(Py_buffer *const *bufs) {
    for (; *bufs; bufs++) PyBuffer_Release(*bufs);
}

static PyObject *segments_clear(PyObject *Py_UNUSED(self), PyObject *args) {
    Py_buffer q, segs, circ, rad, ok;
    if (!PyArg_ParseTuple(args, "y*y*y*y*w*", &q, &segs, &circ, &rad, &ok)) return NULL;
    Py_buffer *all[] = {&q, &segs, &circ, &rad, &ok, NULL};
    Py_ssize_t nq = q.len / (Py_ssize_t)(4 * sizeof(double));
    Py_ssize_t ns = segs.len / (Py_ssize_t)(4 * sizeof(double));
    Py_ssize_t nc = circ.len / (Py_ssize_t)(3 * sizeof(double));
    if (rad.len < nq * (Py_ssize_t)sizeof(double) || ok.len < nq) {
        release(all);
        PyErr_SetString(PyExc_ValueError, "segments_clear: rad and ok need one item per query");
        return NULL;
    }
    const double *Q = q.buf, *S = segs.buf, *C = circ.buf, *R = rad.buf;
    char *out = ok.buf;
    for (Py_ssize_t i = 0; i < nq; i++) {
        double ax = Q[4 * i], ay = Q[4 * i + 1], bx = Q[4 * i + 2], by = Q[4 * i + 3];
        double r2 = R[i] * R[i];
        double ux = bx - ax, uy = by - ay, lu = ux * ux + uy * uy;
        int clear = 1;
        for (Py_ssize_t j = 0; j < ns && clear; j++) {
            double cx = S[4 * j], cy = S[4 * j + 1], dx = S[4 * j + 2], dy = S[4 * j + 3];
            double vx = dx - cx, vy = dy - cy, lv = vx * vx + vy * vy;
            double m = nmin(nmin(d2(ax, ay, cx, cy, vx, vy, lv), d2(bx, by, cx, cy, vx, vy, lv)),
                            nmin(d2(cx, cy, ax, ay, ux, uy, lu), d2(dx, dy, ax, ay, ux, uy, lu)));
            double o1 = ux * (cy - ay) - uy * (cx - ax);
            double o2 = ux * (dy - ay) - uy * (dx - ax);
            double o3 = vx * (ay - cy) - vy * (ax - cx);
            double o4 = vx * (by - cy) - vy * (bx - cx);
            if ((o1 * o2 < 0 && o3 * o4 < 0) || m < r2) clear = 0;
        }
        for (Py_ssize_t k = 0; k < nc && clear; k++) {
            double m = d2(C[3 * k], C[3 * k + 1], ax, ay, ux, uy, lu);
            double rr = R[i] + C[3 * k + 2];
            if (rr < 0.0) rr = 0.0; /* np.maximum(rr, 0): a NaN stays NaN (false here) */
            if (m < rr * rr) clear = 0;
        }
        if (!clear) out[i] = 0;
    }
    release(all);
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"segments_clear", segments_clear, METH_VARARGS, "segments_clear(q, segs, circ, rad, ok)"},
    {NULL, NULL, 0, NULL},
};

static const char doc[] = "geometry.segments_clear's inner loops (see geometry.py).";
static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, .m_name = "_geometry", .m_doc = doc, .m_size = -1,
                                    .m_methods = methods};

PyMODINIT_FUNC PyInit__geometry(void) {
    return PyModule_Create(&module);
}
