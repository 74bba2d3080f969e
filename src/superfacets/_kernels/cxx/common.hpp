// The compiled kernels' common ground: numpy arrays checked without conversion, the
// binary heap, and the exception that sends a call back to the numba kernel.
//
// Each kernel here is the numba kernel of the same name in superfacets/_kernels, the
// same operations in the same order (tested bit for bit against it). An argument of
// another dtype, layout or byte order is never converted: the call raises Mismatch
// (a TypeError) and superfacets._kernels.native runs the numba kernel instead.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <sched.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <thread>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace py = pybind11;

namespace sfk {

using i64 = std::int64_t;
using i32 = std::int32_t;
constexpr double INF = std::numeric_limits<double>::infinity();

// Raised (as superfacets._kernels._cxx.Mismatch, a TypeError) when an argument is not
// an array of exactly the expected dtype, C-contiguous, in native byte order.
struct Mismatch : std::runtime_error {
    using std::runtime_error::runtime_error;
};

template <class T>
inline bool is_dtype(const py::dtype& d) {
    const py::dtype want = py::dtype::of<T>();
    char order = d.byteorder();
    bool native = order == '=' || order == '|' || order == '<';  // x86-64, aarch64: little
    return d.kind() == want.kind() && d.itemsize() == want.itemsize() && native;
}

template <class T>
inline bool matches(py::handle h) {
    if (!py::isinstance<py::array>(h)) return false;
    auto a = py::reinterpret_borrow<py::array>(h);
    return is_dtype<T>(a.dtype()) && (a.flags() & py::array::c_style);
}

// A read-only view of an argument: its data and its length along axis 0.
template <class T>
struct In {
    const T* p = nullptr;
    i64 n = 0;
    i64 cols = 1;
    In() = default;
    In(py::handle h, const char* name) {
        if (!matches<T>(h)) throw Mismatch(std::string("argument ") + name);
        auto a = py::reinterpret_borrow<py::array>(h);
        p = static_cast<const T*>(a.data());
        n = a.ndim() ? a.shape(0) : 1;
        cols = a.ndim() == 2 ? a.shape(1) : 1;
    }
    const T& operator[](i64 i) const { return p[i]; }
    const T& operator()(i64 i, i64 j) const { return p[i * cols + j]; }
};

// A writable view of an argument (an output, or an array updated in place).
template <class T>
struct Out {
    T* p = nullptr;
    i64 n = 0;
    i64 cols = 1;
    Out() = default;
    Out(py::handle h, const char* name) {
        if (!matches<T>(h)) throw Mismatch(std::string("argument ") + name);
        auto a = py::reinterpret_borrow<py::array>(h);
        if (!a.writeable()) throw Mismatch(std::string("read-only argument ") + name);
        p = static_cast<T*>(a.mutable_data());
        n = a.ndim() ? a.shape(0) : 1;
        cols = a.ndim() == 2 ? a.shape(1) : 1;
    }
    T& operator[](i64 i) const { return p[i]; }
    T& operator()(i64 i, i64 j) const { return p[i * cols + j]; }
};

// f(view) with a read-only view of a float32 or a float64 argument, by its dtype.
template <class F>
auto with_real(py::handle h, const char* name, F&& f) {
    if (matches<float>(h)) return f(In<float>(h, name));
    return f(In<double>(h, name));
}

// f(view) with a read-only view of an int32 or an int64 argument (labels), by its dtype.
template <class F>
auto with_index(py::handle h, const char* name, F&& f) {
    if (matches<i32>(h)) return f(In<i32>(h, name));
    return f(In<i64>(h, name));
}

// Sort a[s:f] ascending (insertion sort for a few entries) and move its distinct values
// to its front; returns their number.
template <class T>
i64 sort_distinct(T* a, i64 s, i64 f) {
    if (f - s > 32) {
        std::sort(a + s, a + f);
    } else {
        for (i64 x = s + 1; x < f; ++x) {
            T h = a[x];
            i64 y = x - 1;
            while (y >= s && a[y] > h) {
                a[y + 1] = a[y];
                --y;
            }
            a[y + 1] = h;
        }
    }
    i64 u = 0;
    for (i64 x = s; x < f; ++x)
        if (u == 0 || a[s + u - 1] != a[x]) a[s + u++] = a[x];
    return u;
}

// geometry.store_unit: out[0:3] = (x, y, z) / norm, zeros where the norm is not positive;
// returns the norm, sqrt((x*x + y*y) + z*z).
inline double store_unit(double* out, double x, double y, double z) {
    double norm = std::sqrt(x * x + y * y + z * z);
    if (norm > 0) {
        out[0] = x / norm;
        out[1] = y / norm;
        out[2] = z / norm;
    } else {
        out[0] = out[1] = out[2] = 0.0;
    }
    return norm;
}

// A new array of n (or n x cols) entries, and a writable view of it.
template <class T>
inline py::array_t<T> fresh(i64 n, Out<T>& view, i64 cols = 0) {
    py::array_t<T> a = cols ? py::array_t<T>({n, cols}) : py::array_t<T>(n);
    view.p = a.mutable_data();
    view.n = n;
    view.cols = cols ? cols : 1;
    return a;
}

// numba's min / max on two values: the second when strictly below (above), else the first.
template <class T>
inline T mn(T a, T b) { return b < a ? b : a; }
template <class T>
inline T mx(T a, T b) { return b > a ? b : a; }

// The most threads a kernel may use (0: no limit): a run's n_threads, set for the run's
// duration by superfacets._runtime.threads.using (process-wide, as NUMBA_NUM_THREADS).
inline std::atomic<int>& thread_limit() {
    static std::atomic<int> limit{0};
    return limit;
}

// The threads of a parallel loop: SUPERFACETS_KERNEL_THREADS where set (the compiled
// kernels' alone: the tests' thread counts, which numba, refusing a new NUMBA_NUM_THREADS
// once its threads run, never reads), else NUMBA_NUM_THREADS where set (as numba's prange
// would use; the Dask workers set 1), else the CPUs this process may run on; at most the
// run's limit.
inline int threads() {
    int n = 0;
    if (const char* env = std::getenv("SUPERFACETS_KERNEL_THREADS")) n = std::atoi(env);
    if (n < 1)
        if (const char* env = std::getenv("NUMBA_NUM_THREADS")) n = std::atoi(env);
    if (n < 1) {
        cpu_set_t set;
        n = sched_getaffinity(0, sizeof(set), &set) == 0
                ? std::max(1, CPU_COUNT(&set))
                : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    }
    const int limit = thread_limit().load(std::memory_order_relaxed);
    return limit >= 1 && limit < n ? limit : n;
}

// f(lo, hi) over ranges of 0..n on threads (each element on its own: any split gives
// the same arrays). Small loops run on the calling thread. The ranges, eight a thread
// (of 4,096 elements at least), are taken in turn: a thread the machine slows down, or
// whose elements cost more, takes fewer of them.
template <class F>
void parallel_for(i64 n, F f) {
    const i64 t = std::min<i64>(threads(), n / 4096);
    if (t <= 1) {
        f(0, n);
        return;
    }
    const i64 parts = std::min<i64>(8 * t, n / 4096);
    std::atomic<i64> next{0};
    auto work = [&]() {
        for (i64 c = next++; c < parts; c = next++) f(n * c / parts, n * (c + 1) / parts);
    };
    std::vector<std::thread> pool;
    for (i64 w = 1; w < t; ++w) pool.emplace_back(work);
    work();
    for (auto& th : pool) th.join();
}

// f(t) for t = 0 .. n_threads - 1: t = 0 on the calling thread, each other on its own.
template <class F>
void on_threads(i64 n_threads, F f) {
    std::vector<std::thread> pool;
    for (i64 t = 1; t < n_threads; ++t) pool.emplace_back(f, t);
    f(0);
    for (auto& th : pool) th.join();
}

// The binary min-heap of superfacets/_kernels/heap.py ((float key, int value), lazy
// deletion by the caller), each key beside its value (one cache line per visit instead
// of two): the same comparisons and moves, so the same pops in the same order.
struct Heap {
    struct Entry {
        double key;
        i64 val;
    };
    std::vector<Entry> h;
    i64 size = 0;
    explicit Heap(i64 reserve = 0) { h.reserve(static_cast<size_t>(std::max<i64>(reserve, 1))); }
    void push(double key, i64 val) {
        if (size == static_cast<i64>(h.size())) h.push_back({key, val});
        i64 i = size;
        while (i > 0) {
            i64 p = (i - 1) >> 1;
            if (h[p].key <= key) break;
            h[i] = h[p];
            i = p;
        }
        h[i] = {key, val};
        ++size;
    }
    // remove the root (read h[0] first)
    void pop() {
        --size;
        if (size == 0) return;
        Entry last = h[size];
        i64 i = 0;
        while (true) {
            i64 c = 2 * i + 1;
            if (c >= size) break;
            if (c + 1 < size && h[c + 1].key < h[c].key) ++c;
            if (h[c].key >= last.key) break;
            h[i] = h[c];
            i = c;
        }
        h[i] = last;
    }
};

// A circular bucket queue of (element, key) entries, keys >= 0, for the label-correcting
// searches whose result is a fixed point that does not depend on the order of the work
// (each element ends with the least float sum over paths, ties broken by a total order):
// buckets about a quarter of the median weight wide (a strided sample), as many as put
// an entry at most wmax / width + 1 buckets ahead of the one being emptied. One object
// serves many searches: reset() (when empty) starts the next from bucket 0.
class BucketQueue {
  public:
    BucketQueue(const double* w, i64 n_w) {
        const i64 step = std::max<i64>(1, n_w >> 17);
        std::vector<double> sample;
        double wmax = 0.0;
        for (i64 e = 0; e < n_w; ++e) wmax = std::max(wmax, w[e]);
        for (i64 e = 0; e < n_w; e += step)
            if (w[e] > 0) sample.push_back(w[e]);
        double width = 1.0;
        if (!sample.empty()) {
            auto mid = sample.begin() + static_cast<i64>(sample.size()) / 2;
            std::nth_element(sample.begin(), mid, sample.end());
            width = 0.25 * *mid;
        }
        width = std::max(width, wmax / static_cast<double>((i64{1} << 16) - 2));
        if (!(width > 0.0 && width < INF)) width = 1.0;
        inv_width_ = 1.0 / width;
        i64 nb = 2;
        while (static_cast<double>(nb) < wmax * inv_width_ + 2.0) nb *= 2;
        head_.assign(nb, -1);
        mask_ = nb - 1;
    }

    bool empty() const { return live_ == 0; }

    void reset() {  // (empty: every bucket's list ended)
        cur_ = 0;
        face_.clear();
        next_.clear();
        key_.clear();
        free_ = -1;
    }

    void push(i64 g, double key) {
        i64 n = free_;
        if (n >= 0) {
            free_ = next_[n];
        } else {
            n = static_cast<i64>(face_.size());
            face_.push_back(0);
            next_.push_back(0);
            key_.push_back(0.0);
        }
        i64 i = static_cast<i64>(key * inv_width_);
        if (i < cur_) i = cur_;
        face_[n] = g;
        key_[n] = key;
        next_[n] = head_[i & mask_];
        head_[i & mask_] = n;
        ++live_;
    }

    // the next entry (the queue not empty): of the lowest bucket, its keys within a width
    void pop(i64& g, double& key) {
        while (head_[cur_ & mask_] < 0) ++cur_;
        const i64 b = cur_ & mask_, n = head_[b];
        head_[b] = next_[n];
        next_[n] = free_;
        free_ = n;
        --live_;
        g = face_[n];
        key = key_[n];
    }

  private:
    double inv_width_ = 1.0;
    i64 mask_ = 1, cur_ = 0, free_ = -1, live_ = 0;
    std::vector<i64> head_, face_, next_;
    std::vector<double> key_;
};

// Binding registrations, one per source file.
void bind_graph(py::module_& m);
void bind_expand(py::module_& m);
void bind_sampling(py::module_& m);
void bind_splitmerge(py::module_& m);
void bind_cleanup(py::module_& m);
void bind_voronoi(py::module_& m);
void bind_points(py::module_& m);
void bind_hierarchy(py::module_& m);
void bind_exact(py::module_& m);
void bind_vertices(py::module_& m);
void bind_nearest(py::module_& m);
void bind_order(py::module_& m);
void bind_orient(py::module_& m);

}  // namespace sfk
