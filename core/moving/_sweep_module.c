/* core.moving._sweep_filter: the certified first-contact filter (_sweep_filter.c) as a Python
 * extension, built by setup.py with the filter's floating-point flags. Types: _sweep_filter.pyi.
 *
 * sweep_pairs(d, bodies, pi, pj, shift, status, t_lo, t_hi, iterations): the pairs (pi[k], pj[k])
 * of the rows of bodies, pj's body moved by shift[k] (or shift None), into the outputs; arrays
 * through the buffer protocol (numpy), each checked (element type, shape, C order, writable,
 * indices in range, outputs apart from the inputs: a TypeError or ValueError naming the argument),
 * then the kernel runs with the GIL released, so core/moving/sweep_filter.py splits large batches
 * over threads. The status codes are module constants (NEVER, CONTACT, OVERLAP_AT_START,
 * UNDECIDED).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <string.h>

/* _sweep_filter.c */
int32_t sweep_batch(int32_t d, const double *bodies, int64_t n, int64_t stride, const int64_t *pi, const int64_t *pj,
                    const double *shift, int64_t m, int8_t *status, double *tlo, double *thi, int32_t *iters);

extern const int8_t SWEEP_STATUS_CODES[4]; /* NEVER, CONTACT, OVERLAP_AT_START, UNDECIDED */

/* numpy's name of a buffer's element type ("float32", "int64", ...), or its struct format */
static void describe(const Py_buffer *v, char *out, size_t size) {
    const char *f = v->format ? v->format : "B";
    if (*f == '@' || *f == '=' || *f == '<' || *f == '>' || *f == '!') f++;
    const char *kind = NULL;
    if (f[0] && !f[1]) {
        if (strchr("efd", f[0])) kind = "float";
        else if (strchr("bhilqn", f[0])) kind = "int";
        else if (strchr("BHILQN", f[0])) kind = "uint";
        else if (f[0] == '?') kind = "bool";
    }
    if (kind && strcmp(kind, "bool") == 0) snprintf(out, size, "bool");
    else if (kind) snprintf(out, size, "%s%d", kind, (int)(8 * v->itemsize));
    else snprintf(out, size, "format '%.20s'", v->format ? v->format : "B");
}

/* Whether the buffer's elements are native floats (kind 'f') or signed integers ('i') of itemsize bytes */
static int has_type(const Py_buffer *v, char kind, Py_ssize_t itemsize) {
    const char *f = v->format ? v->format : "B";
    if (*f == '@' || *f == '=') f++;
#if PY_LITTLE_ENDIAN
    else if (*f == '<') f++;
#else
    else if (*f == '>' || *f == '!') f++;
#endif
    if (!f[0] || f[1] || v->itemsize != itemsize) return 0;
    return kind == 'f' ? f[0] == 'd' : strchr("bhilqn", f[0]) != NULL;
}

/* One array argument: view of obj, C-contiguous, of the element type, with ndim dimensions of
 * sizes shape[i] (-1: any; the sizes are written back). 1, or 0 with the error set (nothing held). */
static int get_array(PyObject *obj, Py_buffer *view, const char *name, const char *dtype, char kind, Py_ssize_t itemsize,
                     int ndim, Py_ssize_t *shape, int writable) {
    if (PyObject_GetBuffer(obj, view, PyBUF_RECORDS_RO) < 0) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "sweep_pairs: %s must be an array of %s, got %.100s", name, dtype, Py_TYPE(obj)->tp_name);
        return 0;
    }
    char got[64];
    const char *problem = NULL;
    if (!has_type(view, kind, itemsize)) {
        describe(view, got, sizeof(got));
        PyErr_Format(PyExc_TypeError, "sweep_pairs: %s must be an array of %s, got %s", name, dtype, got);
        PyBuffer_Release(view);
        return 0;
    }
    if (view->ndim != ndim) {
        PyErr_Format(PyExc_ValueError, "sweep_pairs: %s must have %d dimension%s, got %d", name, ndim, ndim == 1 ? "" : "s", view->ndim);
        PyBuffer_Release(view);
        return 0;
    }
    for (int i = 0; i < ndim; i++) {
        if (shape[i] >= 0 && view->shape[i] != shape[i]) {
            if (ndim == 1)
                PyErr_Format(PyExc_ValueError, "sweep_pairs: %s must hold %zd values (one per pair), got %zd", name, shape[0], view->shape[0]);
            else if (shape[0] < 0)
                PyErr_Format(PyExc_ValueError, "sweep_pairs: %s must have shape (N, %zd), got (%zd, %zd)", name, shape[1], view->shape[0],
                             view->shape[1]);
            else
                PyErr_Format(PyExc_ValueError, "sweep_pairs: %s must have shape (%zd, %zd), got (%zd, %zd)", name, shape[0], shape[1],
                             view->shape[0], view->shape[1]);
            PyBuffer_Release(view);
            return 0;
        }
    }
    for (int i = 0; i < ndim; i++) shape[i] = view->shape[i];
    if (!PyBuffer_IsContiguous(view, 'C')) problem = "must be C-contiguous (numpy.ascontiguousarray)";
    else if (writable && view->readonly) problem = "must be writable";
    if (problem) {
        PyErr_Format(PyExc_ValueError, "sweep_pairs: %s %s", name, problem);
        PyBuffer_Release(view);
        return 0;
    }
    return 1;
}

static int overlap(const Py_buffer *a, const Py_buffer *b) {
    const char *x = (const char *)a->buf, *y = (const char *)b->buf;
    return a->len > 0 && b->len > 0 && x < y + b->len && y < x + a->len;
}

static PyObject *sweep_pairs(PyObject *self, PyObject *args) {
    int d;
    PyObject *obj[8]; /* bodies, pi, pj, shift, status, t_lo, t_hi, iterations */
    if (!PyArg_ParseTuple(args, "iOOOOOOOO:sweep_pairs", &d, &obj[0], &obj[1], &obj[2], &obj[3], &obj[4], &obj[5], &obj[6], &obj[7]))
        return NULL;
    if (d != 2 && d != 3) return PyErr_Format(PyExc_ValueError, "sweep_pairs: d must be 2 or 3, got %d", d);
    const Py_ssize_t stride = d == 3 ? 17 : 10; /* c0, c1, r (d each), q0, q1 (4 or 2 each) */
    Py_buffer view[8];
    int held = 0, ok = 1;
    Py_ssize_t shape_b[2] = {-1, stride}, shape_m[1] = {-1}, shape_s[2] = {-1, d};
    static const char *const NAMES[8] = {"bodies", "pi", "pj", "shift", "status", "t_lo", "t_hi", "iterations"};
    /* bodies first, then pi fixes M for the others */
    ok = get_array(obj[0], &view[0], NAMES[0], "float64", 'f', 8, 2, shape_b, 0);
    held += ok;
    if (ok) {
        ok = get_array(obj[1], &view[1], NAMES[1], "int64", 'i', 8, 1, shape_m, 0);
        held += ok;
    }
    const int has_shift = obj[3] != Py_None;
    for (int k = 2; ok && k < 8; k++) {
        if (k == 3 && !has_shift) {
            memset(&view[3], 0, sizeof(Py_buffer));
            held++;
            continue;
        }
        Py_ssize_t one[1] = {shape_m[0]};
        shape_s[0] = shape_m[0];
        if (k == 2) ok = get_array(obj[k], &view[k], NAMES[k], "int64", 'i', 8, 1, one, 0);
        else if (k == 3) ok = get_array(obj[k], &view[k], NAMES[k], "float64", 'f', 8, 2, shape_s, 0);
        else if (k == 4) ok = get_array(obj[k], &view[k], NAMES[k], "int8", 'i', 1, 1, one, 1);
        else if (k == 7) ok = get_array(obj[k], &view[k], NAMES[k], "int32", 'i', 4, 1, one, 1);
        else ok = get_array(obj[k], &view[k], NAMES[k], "float64", 'f', 8, 1, one, 1);
        held += ok;
    }
    PyObject *result = NULL;
    if (ok) {
        const Py_ssize_t n = shape_b[0], m = shape_m[0];
        for (int o = 4; ok && o < 8; o++)
            for (int k = 0; ok && k < 8; k++)
                if (k != o && (k < 4 || k > o) && (k != 3 || has_shift) && overlap(&view[o], &view[k])) {
                    PyErr_Format(PyExc_ValueError, "sweep_pairs: %s shares memory with %s", NAMES[o], NAMES[k]);
                    ok = 0;
                }
        for (int k = 1; ok && k <= 2; k++) {
            const int64_t *idx = (const int64_t *)view[k].buf;
            for (Py_ssize_t p = 0; p < m; p++)
                if (idx[p] < 0 || idx[p] >= n) {
                    PyErr_Format(PyExc_ValueError, "sweep_pairs: %s[%zd] = %lld is not a row of bodies (0 to %zd)", NAMES[k], p,
                                 (long long)idx[p], n - 1);
                    ok = 0;
                    break;
                }
        }
        if (ok) {
            int32_t failed;
            Py_BEGIN_ALLOW_THREADS
            failed = sweep_batch(d, (const double *)view[0].buf, (int64_t)n, (int64_t)stride, (const int64_t *)view[1].buf,
                                 (const int64_t *)view[2].buf, has_shift ? (const double *)view[3].buf : NULL, (int64_t)m,
                                 (int8_t *)view[4].buf, (double *)view[5].buf, (double *)view[6].buf, (int32_t *)view[7].buf);
            Py_END_ALLOW_THREADS
            if (failed) PyErr_SetString(PyExc_MemoryError, "sweep_pairs: no memory for the filter's workspace (about 0.5 MB)");
            else result = Py_NewRef(Py_None);
        }
    }
    for (int k = 0; k < held; k++)
        if (view[k].obj) PyBuffer_Release(&view[k]);
    return result;
}

static PyMethodDef METHODS[] = {
    {"sweep_pairs", sweep_pairs, METH_VARARGS,
     "sweep_pairs(d, bodies, pi, pj, shift, status, t_lo, t_hi, iterations): the certified first-contact filter on the pairs "
     "(pi[k], pj[k]) of the rows of bodies (float64 (N, 17) in 3D, (N, 10) in 2D: c0, c1, r, q0, q1), pj's body moved by "
     "shift[k] (float64 (M, d), or None), into status (int8), t_lo, t_hi (float64) and iterations (int32), each of M values; "
     "the GIL is released while it runs."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef MODULE = {
    PyModuleDef_HEAD_INIT, "_sweep_filter", "The compiled certified float filter of first contacts in linear motion.", -1, METHODS, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__sweep_filter(void) {
    PyObject *m = PyModule_Create(&MODULE);
    if (!m) return NULL;
    static const char *const STATUS[4] = {"NEVER", "CONTACT", "OVERLAP_AT_START", "UNDECIDED"};
    for (int k = 0; k < 4; k++)
        if (PyModule_AddIntConstant(m, STATUS[k], SWEEP_STATUS_CODES[k]) < 0) {
            Py_DECREF(m);
            return NULL;
        }
    return m;
}
