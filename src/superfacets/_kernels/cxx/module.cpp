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
    // each source file a submodule of its name: kernel("geometry.label_sums") is
    // _cxx.geometry.label_sums, defined in geometry.cpp, its reference in
    // tests/oracle/geometry.py
    { nb::module_ s = m.def_submodule("adjacency"); sfk::bind_adjacency(s); }
    { nb::module_ s = m.def_submodule("baselines"); sfk::bind_baselines(s); }
    { nb::module_ s = m.def_submodule("borders"); sfk::bind_borders(s); }
    { nb::module_ s = m.def_submodule("cleanup"); sfk::bind_cleanup(s); }
    { nb::module_ s = m.def_submodule("columns"); sfk::bind_columns(s); }
    { nb::module_ s = m.def_submodule("connectivity"); sfk::bind_connectivity(s); }
    { nb::module_ s = m.def_submodule("exact"); sfk::bind_exact(s); }
    { nb::module_ s = m.def_submodule("expand"); sfk::bind_expand(s); }
    { nb::module_ s = m.def_submodule("farthest"); sfk::bind_farthest(s); }
    { nb::module_ s = m.def_submodule("geometry"); sfk::bind_geometry(s); }
    { nb::module_ s = m.def_submodule("hierarchy"); sfk::bind_hierarchy(s); }
    { nb::module_ s = m.def_submodule("nearest"); sfk::bind_nearest(s); }
    { nb::module_ s = m.def_submodule("normals"); sfk::bind_normals(s); }
    { nb::module_ s = m.def_submodule("orient"); sfk::bind_orient(s); }
    { nb::module_ s = m.def_submodule("splitmerge"); sfk::bind_splitmerge(s); }
    { nb::module_ s = m.def_submodule("terms"); sfk::bind_terms(s); }
    { nb::module_ s = m.def_submodule("update"); sfk::bind_update(s); }
    { nb::module_ s = m.def_submodule("vertices"); sfk::bind_vertices(s); }
    { nb::module_ s = m.def_submodule("voronoi"); sfk::bind_voronoi(s); }
}
