// superfacets._kernels._cxx: the compiled kernels of every run (C++17, nanobind).
#include "common.hpp"

#define SFK_STR2(x) #x
#define SFK_STR(x) SFK_STR2(x)

NB_MODULE(_cxx, m) {
    m.doc() = "Compiled kernels (private): one implementation of each kernel of superfacets.";
    nb::exception<sfk::Mismatch>(m, "Mismatch", PyExc_TypeError);
    nb::exception<sfk::OutOfRange>(m, "OutOfRange", PyExc_ValueError);
    nb::exception<sfk::Interrupted>(m, "Interrupted", PyExc_KeyboardInterrupt);
    // the run's interrupt (a signal's watcher sets it; cleared when the run ends)
    m.def("interrupt", [](int on) { sfk::interrupt_flag().store(on); });
#if defined(__clang__)
    m.attr("compiler") = "clang " __clang_version__;
#elif defined(__GNUC__)
    m.attr("compiler") = "gcc " __VERSION__;
#elif defined(_MSC_VER)
    m.attr("compiler") = "MSVC " SFK_STR(_MSC_VER);
#else
    m.attr("compiler") = "unknown";
#endif
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
    sfk::bind_baselines(m);
}
