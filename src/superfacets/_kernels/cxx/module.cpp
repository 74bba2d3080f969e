// superfacets._kernels._cxx: the compiled kernels of the default runs.
#include "common.hpp"

#ifndef SFK_SOURCES
#define SFK_SOURCES ""
#endif

PYBIND11_MODULE(_cxx, m) {
    m.doc() = "Compiled kernels (private): the numba kernels of the same names, bit for bit.";
    static py::exception<sfk::Mismatch> mismatch(m, "Mismatch", PyExc_TypeError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const sfk::Mismatch& e) {
            py::set_error(mismatch, e.what());
        }
    });
    m.attr("sources_digest") = SFK_SOURCES;  // sha256 of the sources it was built from
    // the run's thread limit (0: none); returns the one it replaces
    m.def("set_thread_limit", [](int n) { return sfk::thread_limit().exchange(n); });
    m.def("threads", &sfk::threads);  // the threads a kernel would use now
    sfk::bind_graph(m);
    sfk::bind_expand(m);
    sfk::bind_sampling(m);
    sfk::bind_splitmerge(m);
    sfk::bind_cleanup(m);
    sfk::bind_voronoi(m);
    sfk::bind_points(m);
    sfk::bind_hierarchy(m);
    sfk::bind_exact(m);
    sfk::bind_vertices(m);
    sfk::bind_nearest(m);
    sfk::bind_order(m);
    sfk::bind_orient(m);
}
