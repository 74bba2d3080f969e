// The compiled kernels' common ground: numpy arrays read through the buffer protocol and
// checked without conversion, the threads, the binary heap and the bucket queue.
//
// Each kernel here has a reference kernel of the same name in tests/oracle (numba): the
// same operations in the same order, tested bit for bit against it. An argument of
// another dtype, layout or byte order is never converted: the call raises Mismatch
// (a TypeError naming the argument) before touching any array.
#pragma once

#include <cerrno>
#include <nanobind/nanobind.h>

#if defined(__linux__)
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>
#endif

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <mutex>
#include <limits>
#include <stdexcept>
#include <string>
#include <system_error>
#include <type_traits>
#include <vector>

namespace nb = nanobind;

namespace sfk {

using i64 = std::int64_t;
using i32 = std::int32_t;
constexpr double INF = std::numeric_limits<double>::infinity();

// Raised (as superfacets._kernels._cxx.Mismatch, a TypeError) when an argument is not
// an array of exactly the expected dtype, C-contiguous, in native byte order: the
// caller converts (the kernels never copy or convert an argument).
struct Mismatch : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Whether a buffer's struct format (PEP 3118, as numpy writes it) is the element type T
// in native byte order (x86-64 and aarch64: little-endian).
template <class T>
inline bool format_is(const char* f, Py_ssize_t itemsize) {
    if (!f || itemsize != static_cast<Py_ssize_t>(sizeof(T))) return false;
    if (*f == '@' || *f == '=' || *f == '<') ++f;
    if (f[0] == '\0' || f[1] != '\0') return false;
    const char c = f[0];
    if constexpr (std::is_same_v<T, bool>) return c == '?';
    else if constexpr (std::is_floating_point_v<T>) return c == (sizeof(T) == 8 ? 'd' : 'f');
    else if constexpr (std::is_signed_v<T>)
        return c == (sizeof(T) == 1 ? 'b' : sizeof(T) == 2 ? 'h' : 0) ||
               ((c == 'i' || c == 'l' || c == 'q') && sizeof(T) >= 4);
    else
        return c == (sizeof(T) == 1 ? 'B' : sizeof(T) == 2 ? 'H' : 0) ||
               ((c == 'I' || c == 'L' || c == 'Q') && sizeof(T) >= 4);
}

// An argument's buffer (the buffer protocol: numpy arrays and their views), read once:
// its data, shape, strides, and whether it is C-contiguous and writable. The caller
// holds the array for the call, so the pointer stays valid after the release.
struct Buffer {
    void* data = nullptr;
    int ndim = 0;
    i64 shape[2] = {1, 1};  // (of the first two axes)
    i64 strides[2] = {0, 0};
    i64 size = 1;
    bool contiguous = false, writable = false;

    template <class T>
    static bool read(nb::handle h, Buffer& b) {
        if (!h.is_valid() || !PyObject_CheckBuffer(h.ptr())) return false;
        Py_buffer v;
        if (PyObject_GetBuffer(h.ptr(), &v, PyBUF_RECORDS_RO) != 0) {
            PyErr_Clear();
            return false;
        }
        bool ok = format_is<T>(v.format, v.itemsize);
        if (ok) {
            b.data = v.buf;
            b.ndim = v.ndim;
            b.size = 1;
            for (int d = 0; d < v.ndim; ++d) {
                if (d < 2) {
                    b.shape[d] = v.shape[d];
                    b.strides[d] = v.strides ? v.strides[d] : 0;
                }
                b.size *= v.shape[d];
            }
            b.contiguous = PyBuffer_IsContiguous(&v, 'C') != 0;
            b.writable = !v.readonly;
        }
        PyBuffer_Release(&v);
        return ok;
    }
};

template <class T>
inline bool matches(nb::handle h) {
    Buffer b;
    return Buffer::read<T>(h, b) && b.contiguous;
}

// A read-only view of an argument: its data and its length along axis 0.
template <class T>
struct In {
    const T* p = nullptr;
    i64 n = 0;
    i64 cols = 1;
    In() = default;
    In(const T* p_, i64 n_, i64 cols_ = 1) : p(p_), n(n_), cols(cols_) {}  // a part of one
    In(nb::handle h, const char* name) {
        Buffer b;
        if (!Buffer::read<T>(h, b) || !b.contiguous)
            throw Mismatch(std::string("argument ") + name);
        p = static_cast<const T*>(b.data);
        n = b.ndim ? b.shape[0] : 1;
        cols = b.ndim == 2 ? b.shape[1] : 1;
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
    Out(nb::handle h, const char* name) {
        Buffer b;
        if (!Buffer::read<T>(h, b) || !b.contiguous)
            throw Mismatch(std::string("argument ") + name);
        if (!b.writable) throw Mismatch(std::string("read-only argument ") + name);
        p = static_cast<T*>(b.data);
        n = b.ndim ? b.shape[0] : 1;
        cols = b.ndim == 2 ? b.shape[1] : 1;
    }
    T& operator[](i64 i) const { return p[i]; }
    T& operator()(i64 i, i64 j) const { return p[i * cols + j]; }
};

// Raised (as superfacets._kernels._cxx.OutOfRange, a ValueError) when an argument's
// entries would take a kernel outside an array: an index past its end or negative, an
// indptr that is not monotone, a length that does not match. Every kernel checks the
// indices it follows at its entry, before any work, whatever it is given.
struct OutOfRange : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Every entry of a (its first `count` entries, all where count < 0) within [lo, hi).
template <class V>
void check_range(const V& a, i64 lo, i64 hi, const char* name, i64 count = -1) {
    const i64 n = count < 0 ? a.n * a.cols : std::min(count, a.n * a.cols);
    if (count > a.n * a.cols)
        throw OutOfRange(std::string("argument ") + name + ": " + std::to_string(a.n * a.cols) +
                         " entries, " + std::to_string(count) + " needed");
    using T = std::remove_cv_t<std::remove_reference_t<decltype(a.p[0])>>;
    T low = n ? a.p[0] : T(0), high = low;
    for (i64 i = 0; i < n; ++i) {  // (branch-free: vectorized)
        low = a.p[i] < low ? a.p[i] : low;
        high = a.p[i] > high ? a.p[i] : high;
    }
    if (n && (static_cast<long double>(low) < lo || static_cast<long double>(high) >= hi)) {
        for (i64 i = 0; i < n; ++i)
            if (static_cast<long double>(a.p[i]) < lo || static_cast<long double>(a.p[i]) >= hi)
                throw OutOfRange(std::string("argument ") + name + ": entry " +
                                 std::to_string(i) + " is " + std::to_string(a.p[i]) +
                                 ", outside " + std::to_string(lo) + ".." + std::to_string(hi - 1));
    }
}

// An array's length along axis 0 is at least (exactly, with exact) `need`.
template <class V>
void check_rows(const V& a, i64 need, const char* name, bool exact = false) {
    if (a.n < need || (exact && a.n != need))
        throw OutOfRange(std::string("argument ") + name + ": " + std::to_string(a.n) +
                         " rows, " + (exact ? "" : "at least ") + std::to_string(need) +
                         " needed");
}

// A compressed-row graph that stays inside its arrays: indptr has n_rows + 1 entries (all
// of them where n_rows < 0), starts at 0 or above, never falls, ends within indices; the
// entries it spans are within [0, n_cols). Returns n_rows.
template <class P, class J>
i64 check_csr(const P& indptr, const J& indices, i64 n_rows, i64 n_cols,
              const char* name = "indptr") {
    if (n_rows < 0) n_rows = indptr.n - 1;
    if (n_rows < 0 || indptr.n < n_rows + 1)
        throw OutOfRange(std::string("argument ") + name + ": " + std::to_string(indptr.n) +
                         " entries for " + std::to_string(n_rows) + " rows");
    if (indptr.p[0] < 0) throw OutOfRange(std::string("argument ") + name + ": negative start");
    bool falls = false;
    for (i64 r = 0; r < n_rows; ++r) falls |= indptr.p[r + 1] < indptr.p[r];
    if (falls) throw OutOfRange(std::string("argument ") + name + ": entries that fall");
    if (static_cast<i64>(indptr.p[n_rows]) > indices.n * indices.cols)
        throw OutOfRange(std::string("argument ") + name + ": ends at " +
                         std::to_string(indptr.p[n_rows]) + ", past the " +
                         std::to_string(indices.n * indices.cols) + " entries of its indices");
    using J_ = std::remove_cv_t<std::remove_reference_t<decltype(indices.p[0])>>;
    check_range(In<J_>(indices.p + indptr.p[0], indptr.p[n_rows] - indptr.p[0]), 0, n_cols,
                "indices");
    return n_rows;
}

// 0 <= lo <= hi <= each of the lengths: a range of rows a kernel is given
inline void check_span(i64 lo, i64 hi, i64 n1, i64 n2) {
    if (lo < 0 || hi < lo || hi > n1 || hi > n2)
        throw OutOfRange("arguments lo, hi: rows " + std::to_string(lo) + ".." +
                         std::to_string(hi) + " of " + std::to_string(std::min(n1, n2)));
}

// The edges (m x 2 vertex numbers) of vertices (n x 3), and out, an entry per edge.
template <class V, class E, class O>
void check_lengths(const V& v, const E& e, const O& out) {
    if (v.cols != 3 || e.cols != 2) throw Mismatch("argument edges");
    check_rows(out, e.n, "out");
    check_range(e, 0, v.n, "edges");
}

// The number of entries of an array argument (0 where it is none).
inline i64 size_of(nb::handle h) {
    if (!h.is_valid() || !PyObject_CheckBuffer(h.ptr())) return 0;
    Py_buffer v;
    if (PyObject_GetBuffer(h.ptr(), &v, PyBUF_RECORDS_RO) != 0) {
        PyErr_Clear();
        return 0;
    }
    i64 s = 1;
    for (int d = 0; d < v.ndim; ++d) s *= v.shape[d];
    PyBuffer_Release(&v);
    return s;
}

// f(view) with a read-only view of a float32 or a float64 argument, by its dtype.
template <class F>
auto with_real(nb::handle h, const char* name, F&& f) {
    if (matches<float>(h)) return f(In<float>(h, name));
    return f(In<double>(h, name));
}

// f(view) with a read-only view of an int32 or an int64 argument (labels), by its dtype.
template <class F>
auto with_index(nb::handle h, const char* name, F&& f) {
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

// numpy's name of the element type T
template <class T>
constexpr const char* dtype_name() {
    if constexpr (std::is_same_v<T, bool>) return "bool";
    else if constexpr (std::is_same_v<T, double>) return "float64";
    else if constexpr (std::is_same_v<T, float>) return "float32";
    else if constexpr (std::is_same_v<T, i64>) return "int64";
    else if constexpr (std::is_same_v<T, i32>) return "int32";
    else if constexpr (std::is_same_v<T, std::uint64_t>) return "uint64";
    else if constexpr (std::is_same_v<T, std::uint8_t>) return "uint8";
    else return "int8";
}

// A new numpy array of n (or n x cols) entries (numpy.empty: numpy owns it, as every
// other array of a run), and a writable view of it. Called holding the GIL.
template <class T>
inline nb::object fresh(i64 n, Out<T>& view, i64 cols = 0) {
    // (kept for the process's life: never destroyed after the interpreter)
    static nb::object* empty = new nb::object(nb::module_::import_("numpy").attr("empty"));
    nb::object a = cols ? (*empty)(nb::make_tuple(n, cols), dtype_name<T>())
                        : (*empty)(n, dtype_name<T>());
    view = Out<T>(a, "fresh");
    return a;
}

// numba's min / max on two values: the second when strictly below (above), else the first.
template <class T>
inline T mn(T a, T b) { return b < a ? b : a; }
template <class T>
inline T mx(T a, T b) { return b > a ? b : a; }

// The most threads a kernel may use (0: no limit): a run's n_threads, set for the run's
// duration by superfacets._runtime.threads.using (process-wide).
inline std::atomic<int>& thread_limit() {
    static std::atomic<int> limit{0};
    return limit;
}

// The threads of a parallel loop: SUPERFACETS_KERNEL_THREADS where set (the kernels'
// alone: the tests' thread counts), else SUPERFACETS_NUM_THREADS where set (the package's
// default thread count; the Dask workers set 1), else the CPUs this process may run on;
// at most the run's limit.
// A thread count from the environment: a whole number from 1 to 4096 alone (what Python's
// check_threads takes: "1e3", "2.5" or 2**63 are no count), else 0.
inline int env_threads(const char* name) {
    const char* env = std::getenv(name);
    if (env == nullptr || *env == '\0') return 0;
    char* end = nullptr;
    errno = 0;
    const long v = std::strtol(env, &end, 10);
    while (end != nullptr && (*end == ' ' || *end == '\t' || *end == '\n')) ++end;
    if (errno != 0 || end == env || *end != '\0' || v < 1 || v > 4096) return 0;
    return static_cast<int>(v);
}

// The threads (the calling one included) whose stacks fit in half the address space
// this process has left under a limit (ulimit -v); 0: no limit. Beyond them a thread
// that starts can find no room for its thread-local data, which glibc does not refuse
// but aborts on; superfacets._runtime.threads.stack_room_threads is the same rule.
inline int address_space_threads() {
#if defined(__linux__)
    struct rlimit as;
    if (getrlimit(RLIMIT_AS, &as) != 0 || as.rlim_cur == RLIM_INFINITY) return 0;
    long pages = 0;
    if (FILE* f = std::fopen("/proc/self/statm", "r")) {
        if (std::fscanf(f, "%ld", &pages) != 1) pages = 0;
        std::fclose(f);
    }
    const double room = static_cast<double>(as.rlim_cur) -
                        static_cast<double>(pages) * static_cast<double>(sysconf(_SC_PAGESIZE));
    struct rlimit st;
    double stack = 8.0 * 1024 * 1024;  // (glibc's default where the stack is unlimited)
    if (getrlimit(RLIMIT_STACK, &st) == 0 && st.rlim_cur != RLIM_INFINITY)
        stack = std::max(65536.0, static_cast<double>(st.rlim_cur));
    if (room <= 2 * stack) return 1;
    return 1 + static_cast<int>(std::min(4095.0, 0.5 * room / stack));
#else
    return 0;
#endif
}

inline int threads() {
    int n = env_threads("SUPERFACETS_KERNEL_THREADS");
    if (n < 1) n = env_threads("SUPERFACETS_NUM_THREADS");
    if (n < 1) {
#if defined(__linux__)
        cpu_set_t set;
        n = sched_getaffinity(0, sizeof(set), &set) == 0
                ? std::max(1, CPU_COUNT(&set))
                : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
#else
        n = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
#endif
    }
    const int fit = address_space_threads();
    if (fit >= 1 && fit < n) n = fit;
    const int limit = thread_limit().load(std::memory_order_relaxed);
    return limit >= 1 && limit < n ? limit : n;
}

// A run interrupted (SIGINT, SIGTERM): set by superfacets._runtime.interrupts'
// SignalWatch (the kernels hold no GIL, so Python's handlers wait for them to return),
// read by the kernels' long loops, which then stop within milliseconds: Interrupted,
// raised as a KeyboardInterrupt.
struct Interrupted : std::runtime_error {
    Interrupted() : std::runtime_error("interrupted") {}
};

inline std::atomic<int>& interrupt_flag() {
    static std::atomic<int> flag{0};
    return flag;
}

inline void check_interrupt() {
    if (interrupt_flag().load(std::memory_order_relaxed)) throw Interrupted();
}

// check_interrupt every 2**16 calls of tick() (a loop's cheap count)
struct Poll {
    std::uint32_t n = 0;
    void tick() {
        if (((++n) & 0xFFFF) == 0) check_interrupt();
    }
};

// The first exception of a parallel loop's threads (std::bad_alloc under a memory
// limit, say), kept until every thread has ended and then thrown on the calling thread:
// an exception must not leave a thread's function, nor unwind past running threads.
class FirstError {
  public:
    template <class G>
    void run(G&& g) {
        try {
            g();
        } catch (...) {
            std::lock_guard<std::mutex> lock(m_);
            if (!error_) error_ = std::current_exception();
        }
    }
    void rethrow() {
        if (error_) std::rethrow_exception(error_);
    }

  private:
    std::mutex m_;
    std::exception_ptr error_;
};

// Start a thread running g into pool; false where the system refuses one (std::thread
// throws std::system_error, EAGAIN, under ulimit -u or -v): the caller runs that work.
template <class G>
inline bool start_thread(std::vector<std::thread>& pool, G&& g) {
    try {
        pool.emplace_back(std::forward<G>(g));
        return true;
    } catch (const std::system_error&) {
        return false;
    }
}

// f(lo, hi) over ranges of 0..n on threads (each element on its own: any split gives
// the same arrays). Small loops run on the calling thread. The ranges, eight a thread
// (of 4,096 elements at least), are taken in turn: a thread the machine slows down, or
// whose elements cost more, takes fewer of them.
template <class F>
void parallel_for(i64 n, F f) {
    const i64 t = std::min<i64>(threads(), n / 4096);
    if (t <= 1) {
        check_interrupt();
        f(0, n);
        return;
    }
    // (and ranges of at most 65,536 elements: a run interrupted stops within one)
    const i64 parts = std::min<i64>(std::max<i64>(8 * t, n / 65536), n / 4096);
    std::atomic<i64> next{0};
    FirstError error;
    auto work = [&]() {
        error.run([&]() {
            for (i64 c = next++; c < parts; c = next++) {
                check_interrupt();
                f(n * c / parts, n * (c + 1) / parts);
            }
        });
    };
    std::vector<std::thread> pool;
    for (i64 w = 1; w < t; ++w)
        if (!start_thread(pool, work)) break;  // the others take its ranges
    work();
    for (auto& th : pool) th.join();
    error.rethrow();
}

// f(t) for t = 0 .. n_threads - 1: t = 0 on the calling thread, each other on its own.
// A thread the system will not start (a limit on processes or memory) runs its call on
// the calling thread after f(0): each t's work is its own, so the same results.
template <class F>
void on_threads(i64 n_threads, F f) {
    std::vector<std::thread> pool;
    std::vector<i64> here;
    FirstError error;
    for (i64 t = 1; t < n_threads; ++t)
        if (!start_thread(pool, [&f, &error, t]() { error.run([&]() { f(t); }); }))
            here.push_back(t);
    error.run([&]() { f(0); });
    for (i64 t : here) error.run([&]() { f(t); });
    for (auto& th : pool) th.join();
    error.rethrow();
}

// The binary min-heap of tests/oracle/heap.py ((float key, int value), lazy
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
    Poll poll;
    // remove the root (read h[0] first)
    void pop() {
        poll.tick();
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
        poll_.tick();
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
    Poll poll_;
    i64 mask_ = 1, cur_ = 0, free_ = -1, live_ = 0;
    std::vector<i64> head_, face_, next_;
    std::vector<double> key_;
};

// Binding registrations, one per source file.
void bind_adjacency(nb::module_& m);
void bind_baselines(nb::module_& m);
void bind_borders(nb::module_& m);
void bind_cleanup(nb::module_& m);
void bind_columns(nb::module_& m);
void bind_connectivity(nb::module_& m);
void bind_exact(nb::module_& m);
void bind_expand(nb::module_& m);
void bind_farthest(nb::module_& m);
void bind_geometry(nb::module_& m);
void bind_hierarchy(nb::module_& m);
void bind_nearest(nb::module_& m);
void bind_normals(nb::module_& m);
void bind_orient(nb::module_& m);
void bind_splitmerge(nb::module_& m);
void bind_terms(nb::module_& m);
void bind_update(nb::module_& m);
void bind_vertices(nb::module_& m);
void bind_voronoi(nb::module_& m);

}  // namespace sfk
