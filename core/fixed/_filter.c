/* core.fixed._filter: the compiled float filter as a Python extension (built by setup.py).
 *
 * The kernels (_kernels.h, generated from core/fixed/driver.py) are compiled three times in one
 * build, for baseline x86-64 (SSE2), AVX2 and AVX-512 (_filter_<variant>.c, chosen by target
 * pragmas), and the best variant this CPU supports is chosen when the module is imported; on
 * other architectures the portable baseline alone is built. ELLIPSOID_SIMD=baseline|avx2|avx512
 * asks for a lower variant (tests compare them). No compiler, cache or thread is needed at run
 * time.
 *
 * classify(n, a, b, out[, table]): a, b C-contiguous float64 or float32 buffers of count * n * n
 * values, out a writable int8 buffer of count rule ids (-1 undecided), or of table[rule id read
 * as a byte] when a 256-byte table is given (the relation codes, written as the block is
 * finished); returns how many pairs are undecided. The GIL is released while the kernels run,
 * so core/fixed/compiled.py splits large batches over threads.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef int64_t (*kernel64)(const double *, const double *, signed char *, int64_t, const signed char *);
typedef int64_t (*kernel32)(const float *, const float *, signed char *, int64_t, const signed char *);

#define DECLARE(v)                                                              \
    int64_t classify3_f64_##v(const double *, const double *, signed char *, int64_t, const signed char *); \
    int64_t classify3_f32_##v(const float *, const float *, signed char *, int64_t, const signed char *);   \
    int64_t classify4_f64_##v(const double *, const double *, signed char *, int64_t, const signed char *); \
    int64_t classify4_f32_##v(const float *, const float *, signed char *, int64_t, const signed char *);
DECLARE(baseline)
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define HAVE_X86_VARIANTS 1
DECLARE(avx2)
DECLARE(avx512)
#endif

typedef struct {
    const char *name;
    kernel64 f64[2]; /* n = 3, 4 */
    kernel32 f32[2];
} variant;

#define VARIANT_ENTRY(v) {#v, {classify3_f64_##v, classify4_f64_##v}, {classify3_f32_##v, classify4_f32_##v}}
static const variant VARIANTS[] = {
    VARIANT_ENTRY(baseline),
#ifdef HAVE_X86_VARIANTS
    VARIANT_ENTRY(avx2),
    VARIANT_ENTRY(avx512),
#endif
};
static const variant *current = &VARIANTS[0];

/* Whether this CPU (and its OS: the compiler's checks include the saved register state) runs a variant. */
static int supported(const char *name) {
    if (strcmp(name, "baseline") == 0) return 1;
#ifdef HAVE_X86_VARIANTS
    __builtin_cpu_init();
    if (strcmp(name, "avx2") == 0) return __builtin_cpu_supports("avx2");
    if (strcmp(name, "avx512") == 0)
        return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl") &&
               __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512cd");
#endif
    return 0;
}

static PyObject *select_variant(PyObject *self, PyObject *args) {
    const char *name;
    if (!PyArg_ParseTuple(args, "s", &name)) return NULL;
    for (size_t i = 0; i < sizeof(VARIANTS) / sizeof(VARIANTS[0]); i++)
        if (strcmp(VARIANTS[i].name, name) == 0) {
            if (!supported(name)) return PyErr_Format(PyExc_ValueError, "this CPU cannot run the %s variant", name);
            current = &VARIANTS[i];
            Py_RETURN_NONE;
        }
    return PyErr_Format(PyExc_ValueError, "unknown SIMD variant %s (this build has: %s)", name, VARIANTS[sizeof(VARIANTS) / sizeof(VARIANTS[0]) - 1].name);
}

static PyObject *get_variant(PyObject *self, PyObject *noargs) { return PyUnicode_FromString(current->name); }

static PyObject *get_variants(PyObject *self, PyObject *noargs) {
    PyObject *out = PyList_New(0);
    if (!out) return NULL;
    for (size_t i = 0; i < sizeof(VARIANTS) / sizeof(VARIANTS[0]); i++)
        if (supported(VARIANTS[i].name)) {
            PyObject *s = PyUnicode_FromString(VARIANTS[i].name);
            if (!s || PyList_Append(out, s) < 0) {
                Py_XDECREF(s);
                Py_DECREF(out);
                return NULL;
            }
            Py_DECREF(s);
        }
    return out;
}

static PyObject *classify(PyObject *self, PyObject *args) {
    int n;
    Py_buffer a, b, out, table = {0};
    if (!PyArg_ParseTuple(args, "iy*y*w*|y*", &n, &a, &b, &out, &table)) return NULL;
    PyObject *result = NULL;
    const Py_ssize_t count = out.len;
    const char *fa = a.format ? a.format : "B", *fb = b.format ? b.format : "B";
    if (n != 3 && n != 4) {
        PyErr_Format(PyExc_ValueError, "n must be 3 or 4, got %d", n);
    } else if (a.itemsize != b.itemsize || (a.itemsize != 8 && a.itemsize != 4)) {
        PyErr_SetString(PyExc_TypeError, "a and b must both be float64 or both float32");
    } else if (a.len != count * n * n * a.itemsize || b.len != a.len) {
        PyErr_Format(PyExc_ValueError, "a and b must hold %zd pairs of %dx%d matrices", count, n, n);
    } else if (table.obj && table.len != 256) {
        PyErr_Format(PyExc_ValueError, "table must hold 256 bytes, got %zd", table.len);
    } else if (!PyBuffer_IsContiguous(&a, 'C') || !PyBuffer_IsContiguous(&b, 'C') || !PyBuffer_IsContiguous(&out, 'C')) {
        PyErr_SetString(PyExc_ValueError, "buffers must be C-contiguous");
    } else {
        (void)fa;
        (void)fb;
        const variant *v = current;
        const signed char *tab = table.obj ? (const signed char *)table.buf : NULL;
        int64_t undecided;
        Py_BEGIN_ALLOW_THREADS
        if (a.itemsize == 8)
            undecided = v->f64[n - 3]((const double *)a.buf, (const double *)b.buf, (signed char *)out.buf, (int64_t)count, tab);
        else
            undecided = v->f32[n - 3]((const float *)a.buf, (const float *)b.buf, (signed char *)out.buf, (int64_t)count, tab);
        Py_END_ALLOW_THREADS
        result = PyLong_FromLongLong((long long)undecided);
    }
    PyBuffer_Release(&a);
    PyBuffer_Release(&b);
    PyBuffer_Release(&out);
    if (table.obj) PyBuffer_Release(&table);
    return result;
}

#ifndef KERNELS_SHA256
#define KERNELS_SHA256 "unknown"
#endif
static PyObject *kernels_sha256(PyObject *self, PyObject *noargs) { return PyUnicode_FromString(KERNELS_SHA256); }

static PyMethodDef METHODS[] = {
    {"kernels_sha256", kernels_sha256, METH_NOARGS, "First 16 hex digits of the SHA-256 of the _kernels.h this module was built from."},
    {"classify", classify, METH_VARARGS, "classify(n, a, b, out[, table]): rule ids (or table[rule id] with a 256-byte table) of count pairs into the int8 buffer out, GIL released; returns how many are undecided."},
    {"variant", get_variant, METH_NOARGS, "The SIMD variant in use."},
    {"variants", get_variants, METH_NOARGS, "The variants of this build that this CPU can run (slowest first)."},
    {"select", select_variant, METH_VARARGS, "select(name): use this variant (ValueError if unknown or unsupported here)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef MODULE = {PyModuleDef_HEAD_INIT, "_filter", "The compiled certified float filter.", -1, METHODS};

PyMODINIT_FUNC PyInit__filter(void) {
    PyObject *m = PyModule_Create(&MODULE);
    if (!m) return NULL;
    /* the best supported variant, unless ELLIPSOID_SIMD asks for another one this CPU runs */
    const char *want = getenv("ELLIPSOID_SIMD");
    for (size_t i = 0; i < sizeof(VARIANTS) / sizeof(VARIANTS[0]); i++)
        if (supported(VARIANTS[i].name)) {
            current = &VARIANTS[i];
            if (want && strcmp(want, VARIANTS[i].name) == 0) break;
        }
    return m;
}
