// Shared helpers of the point kernels (geometry.cpp, normals.cpp, adjacency.cpp, nearest.cpp,
// terms.cpp): eigen-solvers of 3x3 scatters, Morton interleaving, pair terms.
#pragma once
#include <array>
#include <cmath>
#include <cstring>

#include "common.hpp"

namespace sfk {

namespace {

// A 2-D int32 array of any row and column strides (the kNN lists are a column slice).
struct In2i {
    const char* p;
    i64 n, k, s0, s1;
    In2i(nb::handle h, const char* name) {
        Buffer b;
        if (!Buffer::read<i32>(h, b) || b.ndim != 2)
            throw Mismatch(std::string("argument ") + name);
        p = static_cast<const char*>(b.data);
        n = b.shape[0];
        k = b.shape[1];
        s0 = b.strides[0];
        s1 = b.strides[1];
    }
    i32 operator()(i64 i, i64 j) const {
        return *reinterpret_cast<const i32*>(p + i * s0 + j * s1);
    }
    void check(i64 hi, const char* name) const {  // every entry within [0, hi)
        for (i64 i = 0; i < n; ++i)
            for (i64 j = 0; j < k; ++j)
                if ((*this)(i, j) < 0 || (*this)(i, j) >= hi)
                    throw OutOfRange(std::string("argument ") + name + ": entry " +
                                     std::to_string((*this)(i, j)) + " outside 0.." +
                                     std::to_string(hi - 1));
    }
};

inline std::uint64_t spread21(std::uint64_t x) {
    x &= 0x1FFFFFULL;
    x = (x | (x << 32)) & 0x1F00000000FFFFULL;
    x = (x | (x << 16)) & 0x1F0000FF0000FFULL;
    x = (x | (x << 8)) & 0x100F00F00F00F00FULL;
    x = (x | (x << 4)) & 0x10C30C30C30C30C3ULL;
    x = (x | (x << 2)) & 0x1249249249249249ULL;
    return x;
}

// normals.py's closed-form spectrum of a symmetric 3x3 matrix
struct Spectrum {
    double q, p, phi;
};

inline Spectrum spectrum(double a00, double a01, double a02, double a11, double a12,
                         double a22) {
    double p1 = a01 * a01 + a02 * a02 + a12 * a12;
    double q = (a00 + a11 + a22) / 3.0;
    double p2 = (a00 - q) * (a00 - q) + (a11 - q) * (a11 - q) + (a22 - q) * (a22 - q) + 2.0 * p1;
    if (p2 <= 0.0) return {q, 0.0, 0.0};
    double p = std::sqrt(p2 / 6.0);
    double b00 = (a00 - q) / p, b11 = (a11 - q) / p, b22 = (a22 - q) / p;
    double b01 = a01 / p, b02 = a02 / p, b12 = a12 / p;
    double r = 0.5 * (b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) +
                      b02 * (b01 * b12 - b11 * b02));
    r = mn(1.0, mx(-1.0, r));
    return {q, p, std::acos(r) / 3.0};
}

constexpr double PI = 3.141592653589793;

inline void smallest_eigenvector(double a00, double a01, double a02, double a11, double a12,
                                 double a22, double* out) {
    Spectrum sp = spectrum(a00, a01, a02, a11, a12, a22);
    if (sp.p <= 0.0) {
        out[0] = 0.0;
        out[1] = 0.0;
        out[2] = 1.0;
        return;
    }
    double lam = sp.q + 2.0 * sp.p * std::cos(sp.phi + 2.0 * PI / 3.0);
    double r0x = a00 - lam, r0y = a01, r0z = a02;
    double r1x = a01, r1y = a11 - lam, r1z = a12;
    double r2x = a02, r2y = a12, r2z = a22 - lam;
    double c0x = r0y * r1z - r0z * r1y, c0y = r0z * r1x - r0x * r1z, c0z = r0x * r1y - r0y * r1x;
    double c1x = r0y * r2z - r0z * r2y, c1y = r0z * r2x - r0x * r2z, c1z = r0x * r2y - r0y * r2x;
    double c2x = r1y * r2z - r1z * r2y, c2y = r1z * r2x - r1x * r2z, c2z = r1x * r2y - r1y * r2x;
    double d0 = c0x * c0x + c0y * c0y + c0z * c0z;
    double d1 = c1x * c1x + c1y * c1y + c1z * c1z;
    double d2 = c2x * c2x + c2y * c2y + c2z * c2z;
    double x, y, z, d;
    if (d0 >= d1 && d0 >= d2) {
        x = c0x, y = c0y, z = c0z, d = d0;
    } else if (d1 >= d2) {
        x = c1x, y = c1y, z = c1z, d = d1;
    } else {
        x = c2x, y = c2y, z = c2z, d = d2;
    }
    if (d <= 0.0) {
        out[0] = 0.0;
        out[1] = 0.0;
        out[2] = 1.0;
        return;
    }
    double s = 1.0 / std::sqrt(d);
    out[0] = x * s;
    out[1] = y * s;
    out[2] = z * s;
}

template <class I>
inline void scatter(const double* pts, const I* idx, i64 k, double* a) {
    for (int t = 0; t < 6; ++t) a[t] = 0.0;
    if (k == 0) return;
    double mx_ = 0.0, my = 0.0, mz = 0.0;
    for (i64 t = 0; t < k; ++t) {
        i64 j = idx[t];
        mx_ += pts[3 * j];
        my += pts[3 * j + 1];
        mz += pts[3 * j + 2];
    }
    mx_ /= static_cast<double>(k);
    my /= static_cast<double>(k);
    mz /= static_cast<double>(k);
    for (i64 t = 0; t < k; ++t) {
        i64 j = idx[t];
        double x = pts[3 * j] - mx_, y = pts[3 * j + 1] - my, z = pts[3 * j + 2] - mz;
        a[0] += x * x;
        a[1] += x * y;
        a[2] += x * z;
        a[3] += y * y;
        a[4] += y * z;
        a[5] += z * z;
    }
}

// The scatter of the points idx[0:k], divided by its trace where that is positive;
// returns whether it was.
inline bool unit_scatter(const double* pts, const i32* idx, i64 k, double* a) {
    scatter(pts, idx, k, a);
    double scale = a[0] + a[3] + a[5];
    if (!(scale > 0.0)) return false;
    for (int t = 0; t < 6; ++t) a[t] /= scale;
    return true;
}

inline double linearity(double a00, double a01, double a02, double a11, double a12,
                        double a22) {
    Spectrum sp = spectrum(a00, a01, a02, a11, a12, a22);
    if (sp.p <= 0.0 || sp.q <= 0.0) return 0.0;
    double l1 = sp.q + 2.0 * sp.p * std::cos(sp.phi);
    double l3 = sp.q + 2.0 * sp.p * std::cos(sp.phi + 2.0 * PI / 3.0);
    double l2 = 3.0 * sp.q - l1 - l3;
    return l1 > 0.0 ? (l1 - l2) / l1 : 0.0;
}

// geometry.pair_terms (normals float64, or float32 read as float64)
template <class N>
inline void pair_terms(const double* pos, const N* nor, i64 i, i64 j, double& geo,
                       double& cs, bool& concave) {
    double dx = pos[3 * i] - pos[3 * j], dy = pos[3 * i + 1] - pos[3 * j + 1],
           dz = pos[3 * i + 2] - pos[3 * j + 2];
    const double ix = nor[3 * i], iy = nor[3 * i + 1], iz = nor[3 * i + 2];
    const double jx = nor[3 * j], jy = nor[3 * j + 1], jz = nor[3 * j + 2];
    double c = (ix * jx + iz * jz) + iy * jy;
    double s = ((ix - jx) * dx + (iz - jz) * dz) + (iy - jy) * dy;
    geo = std::sqrt(dx * dx + dy * dy + dz * dz);
    cs = mn(mx(c, -1.0), 1.0);
    concave = s < 0;
}

// The 63 x 3 bits of o[0..2], interleaved x, y, z from the top: 21 of each a word.
inline void interleave(const std::uint64_t* o, std::uint64_t* key) {
    for (int w = 0; w < 3; ++w) {
        std::uint64_t s = static_cast<std::uint64_t>(43 - 21 * w);
        key[w] = (spread21(o[0] >> s) << 2) | (spread21(o[1] >> s) << 1) | spread21(o[2] >> s);
    }
}

}  // namespace

}  // namespace sfk
