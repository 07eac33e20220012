/* The Python face of the sweep filter: an empty extension module, so that setuptools builds
 * core/moving/_sweep_filter.c when the package is installed (setup.py) and Python finds the
 * shared library by import. core/moving/sweep_filter.py calls its C function sweep_pairs
 * through ctypes (the library's own path), with the GIL released. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

static struct PyModuleDef sweep_module = {
    PyModuleDef_HEAD_INIT, "_sweep_filter",
    "Certified float filter for first contacts in linear motion (C; called through ctypes).", -1, NULL, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__sweep_filter(void) { return PyModule_Create(&sweep_module); }
