/* The ray caster's inner loops in C: the same algorithm and the same floating-point steps as the numpy
 * version in raycast.py (which stays the reference, the fallback and the tests' oracle).
 *
 * Rules:
 * - Only buffers of float64 / int64 come in (the buffer protocol, no numpy headers); the caller passes C-contiguous
 *   arrays of those types and pre-fills the outputs (ranges inf, hits -1); a buffer shorter than the call needs
 *   is a ValueError, never a read or write past its end.
 * - fan(): angular culling as raycast._intervals/_pairs do it - each segment or circle covers a contiguous run
 *   of beams seen from the origin (plus a run wrapped past 2 pi); only those (beam, owner) pairs are tested,
 *   normal runs of every owner first, then the wrapped runs, so that a tie goes to the owner numpy's
 *   "last write wins" would pick.
 * - rays(): every ray against every segment, then every circle; the first least distance wins (np.argmin).
 * - Built with -ffp-contract=off: no fused multiply-add, so each product rounds as numpy's does.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>

static const double TWO_PI = 2.0 * 3.14159265358979323846;

/* Python's float % for a positive divisor (numpy's remainder): the result has the divisor's sign. */
static double pymod(double a, double b) {
    double m = fmod(a, b);
    if (m != 0.0) {
        if ((b < 0) != (m < 0)) m += b;
    } else {
        m = copysign(0.0, b);
    }
    return m;
}

/* Distance along the unit direction (dx, dy) from the origin to the circle's near surface, (wx, wy) = centre -
 * origin; inf when the line misses it. Negative or zero when the origin is inside or past it (callers test t > 0). */
static double circle_t(double wx, double wy, double r, double dx, double dy) {
    double proj = wx * dx + wy * dy;
    double perp2 = wx * wx + wy * wy - proj * proj;
    double inside = r * r - perp2;
    return perp2 <= r * r ? proj - sqrt(inside > 0.0 ? inside : 0.0) : INFINITY;
}

/* The buffers hold what the call says (the caller's arrays are float64 / int64 of these lengths). */
/* PyBuffer_Release of each buffer of a NULL-terminated list: what every exit of a function does */
static void release(Py_buffer *const *bufs) {
    for (; *bufs; bufs++) PyBuffer_Release(*bufs);
}

static int sized(const Py_buffer *b, Py_ssize_t items, Py_ssize_t item, const char *name) {
    if (b->len < items * item) {
        PyErr_Format(PyExc_ValueError, "%s: %zd bytes, %zd wanted", name, b->len, items * item);
        return 0;
    }
    return 1;
}

typedef struct {
    double x, y, ch, sh, max_range;
    const double *cb, *sb, *segs, *circs;
    Py_ssize_t ns;
    double *ranges;
    int64_t *hits;
} Fan;

static void test_beam(const Fan *f, Py_ssize_t owner, Py_ssize_t b) {
    double bdx = f->cb[b] * f->ch - f->sb[b] * f->sh;
    double bdy = f->sb[b] * f->ch + f->cb[b] * f->sh;
    double t;
    if (owner < f->ns) {
        const double *s = f->segs + 4 * owner;
        double ex = s[2] - s[0], ey = s[3] - s[1];
        double cross = (s[0] - f->x) * ey - (s[1] - f->y) * ex;
        t = cross / (bdx * ey - bdy * ex);
    } else {
        const double *c = f->circs + 3 * (owner - f->ns);
        t = circle_t(c[0] - f->x, c[1] - f->y, c[2], bdx, bdy);
    }
    if (!(t > 0.0 && t <= f->max_range)) return;
    if (t < f->ranges[b]) {
        f->ranges[b] = t;
        f->hits[b] = owner;
    } else if (t == f->ranges[b]) {
        f->hits[b] = owner; /* numpy: the last pair written wins a tie */
    }
}

static PyObject *fan(PyObject *Py_UNUSED(self), PyObject *args) {
    double x, y, a0, heading, step, max_range;
    Py_ssize_t count;
    Py_buffer segs, circs, cb, sb, ranges, hits;
    if (!PyArg_ParseTuple(args, "ddddddny*y*y*y*w*w*", &x, &y, &a0, &heading, &step, &max_range, &count, &segs, &circs,
                          &cb, &sb, &ranges, &hits))
        return NULL;
    Py_buffer *all[] = {&segs, &circs, &cb, &sb, &ranges, &hits, NULL};
    Py_ssize_t ns = segs.len / (Py_ssize_t)(4 * sizeof(double));
    Py_ssize_t nc = circs.len / (Py_ssize_t)(3 * sizeof(double));
    Py_ssize_t n = ns + nc;
    if (!(sized(&cb, count, sizeof(double), "cos_b") && sized(&sb, count, sizeof(double), "sin_b") &&
          sized(&ranges, count, sizeof(double), "ranges") && sized(&hits, count, sizeof(int64_t), "hits"))) {
        release(all);
        return NULL;
    }
    Fan f = {x,      y,        cos(heading), sin(heading), max_range,  cb.buf,
             sb.buf, segs.buf, circs.buf,    ns,           ranges.buf, hits.buf};
    double inv = 1.0 / step, wrap_at = TWO_PI / step, top = (double)(count - 1);
    /* each owner's interval [lo, lo + span] above the first beam, as raycast._intervals */
    double *lo = PyMem_Malloc(sizeof(double) * (size_t)(n > 0 ? 2 * n : 1));
    if (lo == NULL) {
        release(all);
        return PyErr_NoMemory();
    }
    double *span = lo + n;
    for (Py_ssize_t i = 0; i < ns; i++) {
        const double *s = f.segs + 4 * i;
        double p = atan2(s[1] - y, s[0] - x), q = atan2(s[3] - y, s[2] - x);
        p -= a0;
        q -= a0;
        p = pymod(p, TWO_PI);
        q = pymod(q, TWO_PI);
        double d = pymod(q - p, TWO_PI);
        if (d <= 3.14159265358979323846) {
            lo[i] = p;
            span[i] = d;
        } else {
            lo[i] = q;
            span[i] = TWO_PI - d;
        }
    }
    for (Py_ssize_t k = 0; k < nc; k++) {
        const double *c = f.circs + 3 * k;
        double wx = c[0] - x, wy = c[1] - y, r = c[2];
        double dist = hypot(wx, wy);
        double ratio = r / (dist > 1e-9 ? dist : 1e-9);
        ratio = ratio < 0.0 ? 0.0 : (ratio > 1.0 ? 1.0 : ratio);
        double half = dist > r ? asin(ratio) : -1.0;
        lo[ns + k] = pymod(atan2(wy, wx) - a0 - (half > 0.0 ? half : 0.0), TWO_PI);
        span[ns + k] = 2.0 * half;
    }
    for (int pass = 0; pass < 2; pass++) {
        for (Py_ssize_t i = 0; i < n; i++) {
            double lo_b = lo[i] * inv;
            double hi_b = lo_b + span[i] * inv;
            Py_ssize_t first, last;
            if (pass == 0) {
                first = (Py_ssize_t)ceil(lo_b - 1e-9);
                last = (Py_ssize_t)floor((hi_b < top ? hi_b : top) + 1e-9);
            } else {
                double w = hi_b - wrap_at;
                first = 0;
                last = (Py_ssize_t)floor((w < top ? w : top) + 1e-9);
            }
            for (Py_ssize_t b = first; b <= last; b++) test_beam(&f, i, b);
        }
    }
    PyMem_Free(lo);
    release(all);
    Py_RETURN_NONE;
}

static PyObject *rays(PyObject *Py_UNUSED(self), PyObject *args) {
    double max_range;
    Py_buffer ox, oy, dx, dy, segs, circs, ranges, hits;
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*y*dw*w*", &ox, &oy, &dx, &dy, &segs, &circs, &max_range, &ranges, &hits))
        return NULL;
    Py_buffer *all[] = {&ox, &oy, &dx, &dy, &segs, &circs, &ranges, &hits, NULL};
    Py_ssize_t n = ox.len / (Py_ssize_t)sizeof(double);
    Py_ssize_t ns = segs.len / (Py_ssize_t)(4 * sizeof(double));
    Py_ssize_t nc = circs.len / (Py_ssize_t)(3 * sizeof(double));
    if (!(sized(&oy, n, sizeof(double), "oy") && sized(&dx, n, sizeof(double), "dx") &&
          sized(&dy, n, sizeof(double), "dy") && sized(&ranges, n, sizeof(double), "ranges") &&
          sized(&hits, n, sizeof(int64_t), "hits"))) {
        release(all);
        return NULL;
    }
    const double *px = ox.buf, *py = oy.buf, *vx = dx.buf, *vy = dy.buf, *s = segs.buf, *c = circs.buf;
    double *out = ranges.buf;
    int64_t *ids = hits.buf;
    for (Py_ssize_t i = 0; i < n; i++) {
        double best = INFINITY;
        Py_ssize_t arg = 0;
        for (Py_ssize_t j = 0; j < ns; j++) {
            const double *g = s + 4 * j;
            double wx = g[0] - px[i], wy = g[1] - py[i];
            double ex = g[2] - g[0], ey = g[3] - g[1];
            double den = vx[i] * ey - vy[i] * ex;
            double t = (wx * ey - wy * ex) / den;
            double u = (wx * vy[i] - wy * vx[i]) / den;
            if (t > 0.0 && u >= 0.0 && u <= 1.0 && t < best) {
                best = t;
                arg = j;
            }
        }
        for (Py_ssize_t k = 0; k < nc; k++) {
            const double *g = c + 3 * k;
            double t = circle_t(g[0] - px[i], g[1] - py[i], g[2], vx[i], vy[i]);
            if (t > 0.0 && t < best) {
                best = t;
                arg = ns + k;
            }
        }
        if (best <= max_range) {
            out[i] = best;
            ids[i] = arg;
        } else {
            out[i] = INFINITY;
            ids[i] = -1;
        }
    }
    release(all);
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"fan", fan, METH_VARARGS,
     "fan(x, y, a0, heading, step, max_range, count, segs, circs, cos_b, sin_b, ranges, hits)"},
    {"rays", rays, METH_VARARGS, "rays(ox, oy, dx, dy, segs, circs, max_range, ranges, hits)"},
    {NULL, NULL, 0, NULL},
};

static const char doc[] = "The ray caster's inner loops (see raycast.py).";
static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, .m_name = "_raycast", .m_doc = doc, .m_size = -1,
                                    .m_methods = methods};

PyMODINIT_FUNC PyInit__raycast(void) {
    return PyModule_Create(&module);
}
