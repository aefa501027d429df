// Plain C++ peer for gmueller's Jones -> Mueller closed form (see validation/peers/README.md).
//
// Closed form of M_kl = 1/2 tr(sigma_k J sigma_l J^dagger) over a structure-of-arrays batch,
// with sigma_0 = I, sigma_1 = diag(1, -1), sigma_2 = [[0, 1], [1, 0]], sigma_3 = [[0, -i], [i, 0]]
// (the convention of gmueller's Mueller::from_jones). For J = [[a, b], [c, d]]:
//
//   M00 = 1/2 (|a|^2 + |b|^2 + |c|^2 + |d|^2)   M01 = 1/2 (|a|^2 - |b|^2 + |c|^2 - |d|^2)
//   M10 = 1/2 (|a|^2 + |b|^2 - |c|^2 - |d|^2)   M11 = 1/2 (|a|^2 - |b|^2 - |c|^2 + |d|^2)
//   M02 = Re(a b*) + Re(c d*)                   M03 = Im(a b*) + Im(c d*)
//   M12 = Re(a b*) - Re(c d*)                   M13 = Im(a b*) - Im(c d*)
//   M20 = Re(a c*) + Re(b d*)                   M21 = Re(a c*) - Re(b d*)
//   M30 = -Im(a c*) - Im(b d*)                  M31 = -Im(a c*) + Im(b d*)
//   M22 = Re(b c*) + Re(a d*)                   M23 = Im(a d*) - Im(b c*)
//   M32 = -Im(b c*) - Im(a d*)                  M33 = Re(a d*) - Re(b c*)
//
// (From H_l = J sigma_l J^dagger: M_0l = 1/2 (H11 + H22), M_1l = 1/2 (H11 - H22),
//  M_2l = Re H12, M_3l = -Im H12, with H12 = a c* + b d*, a c* - b d*, b c* + a d*,
//  i (b c* - a d*) for l = 0..3.)
//
// Before timing, the closed form is checked against two literal 4x4 complex computations in
// double: the trace formula above and A (J* (x) J) A^-1 with the S1.3 matrix A (gmueller's a_mul).
// Then it times N = 1024 matrices (the 24 streams, 192 KiB in f64 and 96 KiB in f32, stay in L2)
// in f64 and f32 with std::chrono, for two memory layouts (see Layout), and prints
// "precision layout N median_ns_per_matrix min_ns_per_matrix samples": 201 samples of ~2 ms,
// each a calibrated number of back-to-back batch calls.
//
// Build: g++ -O3 -std=c++17 [-march=native] validation/peers/jones_mueller_soa.cpp -o target/peers/jm

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {

// SplitMix64: deterministic inputs in [-1, 1).
struct SplitMix {
    std::uint64_t s;
    double next() {
        s += 0x9E3779B97F4A7C15ull;
        std::uint64_t z = s;
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        z ^= z >> 31;
        return static_cast<double>(z >> 11) / static_cast<double>(1ull << 53) * 2.0 - 1.0;
    }
};

// 24 streams of n values: 8 inputs (re/im of a, b, c, d) then 16 outputs (M00, M01, ..., M33).
// Layout::Separate: one std::vector per stream (malloc places them ~n*sizeof(T) apart, so for
// n = 1024 every stream starts at the same offset modulo 4096 and they share L1 sets).
// Layout::Staggered: one 64-byte-aligned arena, stream s starting s cache lines after a multiple
// of n*sizeof(T), so the 24 streams fall in different L1 sets.
enum class Layout { Separate, Staggered };

template <typename T>
struct Batch {
    std::size_t n;
    std::vector<std::vector<T>> separate;
    std::vector<T> arena;
    std::array<T*, 24> s{};
    Batch(std::size_t n_, Layout layout) : n(n_) {
        if (layout == Layout::Separate) {
            separate.assign(24, std::vector<T>(n, T(0)));
            for (int k = 0; k < 24; ++k) s[k] = separate[k].data();
        } else {
            const std::size_t line = 64 / sizeof(T);
            arena.assign(24 * (n + line) + line, T(0));
            T* base = arena.data();
            while (reinterpret_cast<std::uintptr_t>(base) % 64 != 0) ++base;
            for (std::size_t k = 0; k < 24; ++k) s[k] = base + k * (n + line);
        }
    }
    T* re(int e) const { return s[2 * e]; }
    T* im(int e) const { return s[2 * e + 1]; }
    T* out(int k) const { return s[8 + k]; }
};

template <typename T>
__attribute__((noinline)) void mueller_from_jones_soa(std::size_t n, const T* __restrict ar,
                                                      const T* __restrict ai, const T* __restrict br,
                                                      const T* __restrict bi, const T* __restrict cr,
                                                      const T* __restrict ci, const T* __restrict dr,
                                                      const T* __restrict di, T* const* out) {
    T* __restrict m00 = out[0];
    T* __restrict m01 = out[1];
    T* __restrict m02 = out[2];
    T* __restrict m03 = out[3];
    T* __restrict m10 = out[4];
    T* __restrict m11 = out[5];
    T* __restrict m12 = out[6];
    T* __restrict m13 = out[7];
    T* __restrict m20 = out[8];
    T* __restrict m21 = out[9];
    T* __restrict m22 = out[10];
    T* __restrict m23 = out[11];
    T* __restrict m30 = out[12];
    T* __restrict m31 = out[13];
    T* __restrict m32 = out[14];
    T* __restrict m33 = out[15];
    const T h = T(0.5);
    // The 24 streams are distinct arrays; ivdep tells GCC so (its alias analysis does not use
    // restrict on local pointers), otherwise it does not vectorise the loop.
#pragma GCC ivdep
    for (std::size_t i = 0; i < n; ++i) {
        const T a_r = ar[i], a_i = ai[i], b_r = br[i], b_i = bi[i];
        const T c_r = cr[i], c_i = ci[i], d_r = dr[i], d_i = di[i];
        const T aa = a_r * a_r + a_i * a_i, bb = b_r * b_r + b_i * b_i;
        const T cc = c_r * c_r + c_i * c_i, dd = d_r * d_r + d_i * d_i;
        // x y* = (xr yr + xi yi) + i (xi yr - xr yi)
        const T ab_r = a_r * b_r + a_i * b_i, ab_i = a_i * b_r - a_r * b_i;
        const T cd_r = c_r * d_r + c_i * d_i, cd_i = c_i * d_r - c_r * d_i;
        const T ac_r = a_r * c_r + a_i * c_i, ac_i = a_i * c_r - a_r * c_i;
        const T bd_r = b_r * d_r + b_i * d_i, bd_i = b_i * d_r - b_r * d_i;
        const T bc_r = b_r * c_r + b_i * c_i, bc_i = b_i * c_r - b_r * c_i;
        const T ad_r = a_r * d_r + a_i * d_i, ad_i = a_i * d_r - a_r * d_i;
        m00[i] = h * (aa + bb + cc + dd);
        m01[i] = h * (aa - bb + cc - dd);
        m02[i] = ab_r + cd_r;
        m03[i] = ab_i + cd_i;
        m10[i] = h * (aa + bb - cc - dd);
        m11[i] = h * (aa - bb - cc + dd);
        m12[i] = ab_r - cd_r;
        m13[i] = ab_i - cd_i;
        m20[i] = ac_r + bd_r;
        m21[i] = ac_r - bd_r;
        m22[i] = bc_r + ad_r;
        m23[i] = ad_i - bc_i;
        m30[i] = -ac_i - bd_i;
        m31[i] = bd_i - ac_i;
        m32[i] = -bc_i - ad_i;
        m33[i] = ad_r - bc_r;
    }
}

using C = std::complex<double>;
using M2 = std::array<std::array<C, 2>, 2>;
using M4 = std::array<std::array<C, 4>, 4>;

M2 mul2(const M2& x, const M2& y) {
    M2 r{};
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
            for (int k = 0; k < 2; ++k) r[i][j] += x[i][k] * y[k][j];
    return r;
}

M2 dagger(const M2& x) {
    M2 r{};
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) r[i][j] = std::conj(x[j][i]);
    return r;
}

M4 mul4(const M4& x, const M4& y) {
    M4 r{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            for (int k = 0; k < 4; ++k) r[i][j] += x[i][k] * y[k][j];
    return r;
}

// Literal 1: M_kl = 1/2 tr(sigma_k J sigma_l J^dagger), complex; returns the full complex matrix.
M4 literal_trace(const M2& j) {
    const C o(1, 0), z(0, 0), i(0, 1);
    const std::array<M2, 4> s = {M2{{{o, z}, {z, o}}}, M2{{{o, z}, {z, -o}}}, M2{{{z, o}, {o, z}}},
                                 M2{{{z, -i}, {i, z}}}};
    M4 m{};
    for (int k = 0; k < 4; ++k)
        for (int l = 0; l < 4; ++l) {
            const M2 p = mul2(mul2(mul2(s[k], j), s[l]), dagger(j));
            m[k][l] = 0.5 * (p[0][0] + p[1][1]);
        }
    return m;
}

// Literal 2: A (J* (x) J) A^-1 with A = [[1,0,0,1],[1,0,0,-1],[0,1,1,0],[0,-i,i,0]], A^-1 = A^dagger / 2.
M4 literal_kron(const M2& j) {
    const C o(1, 0), z(0, 0), i(0, 1);
    const M4 a = {{{o, z, z, o}, {o, z, z, -o}, {z, o, o, z}, {z, -i, i, z}}};
    M4 ainv{};
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) ainv[r][c] = 0.5 * std::conj(a[c][r]);
    M4 k{};
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) k[r][c] = std::conj(j[r / 2][c / 2]) * j[r % 2][c % 2];
    return mul4(mul4(a, k), ainv);
}

template <typename T>
void fill(const Batch<T>& js, std::uint64_t seed) {
    SplitMix rng{seed};
    for (std::size_t i = 0; i < js.n; ++i)
        for (int e = 0; e < 4; ++e) {
            js.re(e)[i] = static_cast<T>(rng.next());
            js.im(e)[i] = static_cast<T>(rng.next());
        }
}

template <typename T>
void run_kernel(const Batch<T>& js) {
    mueller_from_jones_soa<T>(js.n, js.re(0), js.im(0), js.re(1), js.im(1), js.re(2), js.im(2),
                              js.re(3), js.im(3), js.s.data() + 8);
}

// Checks the closed form (precision T) against both literal forms computed in double from the
// same (rounded-to-T) inputs. Tolerance per entry: abs_tol + rel_tol * |M_lit|; the two literal
// forms must also agree with each other within 1e-14 and have |Im| <= 1e-14. Inputs are in
// [-1, 1) + i[-1, 1), so every entry is a sum of at most 8 products of magnitude <= 2: in f32 the
// rounding error is below 8 * 2 * 2^-23 ~ 2e-6 (abs_tol 2e-6), in f64 below 4e-15 (abs_tol 1e-14).
template <typename T>
bool check(const char* name, double abs_tol, double rel_tol) {
    const std::size_t n = 4096;
    Batch<T> js(n, Layout::Staggered);
    fill(js, 0xC0FFEE);
    run_kernel(js);
    double worst = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        M2 j{};
        for (int e = 0; e < 4; ++e)
            j[e / 2][e % 2] = C(static_cast<double>(js.re(e)[i]), static_cast<double>(js.im(e)[i]));
        const M4 lt = literal_trace(j);
        const M4 lk = literal_kron(j);
        for (int k = 0; k < 4; ++k)
            for (int l = 0; l < 4; ++l) {
                const double got = static_cast<double>(js.out(4 * k + l)[i]);
                const double want = lt[k][l].real();
                if (std::abs(lt[k][l].imag()) > 1e-14 || std::abs(lk[k][l].imag()) > 1e-14 ||
                    std::abs(lk[k][l].real() - want) > 1e-14) {
                    std::fprintf(stderr, "literal forms disagree at i=%zu M%d%d: %g%+gi vs %g%+gi\n", i,
                                 k, l, lt[k][l].real(), lt[k][l].imag(), lk[k][l].real(),
                                 lk[k][l].imag());
                    return false;
                }
                const double err = std::abs(got - want);
                const double tol = abs_tol + rel_tol * std::abs(want);
                worst = std::max(worst, err / tol);
                if (err > tol) {
                    std::fprintf(stderr, "%s closed form wrong at i=%zu M%d%d: %.17g vs literal %.17g\n",
                                 name, i, k, l, got, want);
                    return false;
                }
            }
    }
    std::fprintf(stderr, "check %s: closed form == literal (trace and Kronecker) on %zu matrices, "
                 "worst err/tol = %.3g (abs %.0e + rel %.0e)\n", name, n, worst, abs_tol, rel_tol);
    return true;
}

template <typename T>
void time_it(const char* name, std::size_t n, Layout layout) {
    Batch<T> js(n, layout);
    fill(js, 0x5EED);
    using clock = std::chrono::steady_clock;
    // Calibrate repetitions so one sample lasts about 2 ms.
    std::size_t reps = 1;
    for (;;) {
        const auto t0 = clock::now();
        for (std::size_t r = 0; r < reps; ++r) {
            run_kernel(js);
            asm volatile("" ::: "memory");
        }
        const double dt = std::chrono::duration<double>(clock::now() - t0).count();
        if (dt > 2e-3) break;
        reps *= 2;
    }
    const int samples = 201;
    std::vector<double> ns(samples);
    for (int s = 0; s < samples; ++s) {
        const auto t0 = clock::now();
        for (std::size_t r = 0; r < reps; ++r) {
            run_kernel(js);
            asm volatile("" ::: "memory");
        }
        const double dt = std::chrono::duration<double>(clock::now() - t0).count();
        ns[s] = dt * 1e9 / static_cast<double>(reps * n);
    }
    std::sort(ns.begin(), ns.end());
    double sink = 0.0;  // keeps the result observable
    for (int k = 0; k < 16; ++k) sink += static_cast<double>(js.out(k)[n / 2]);
    std::printf("%s %s %zu %.4f %.4f %d  # checksum %.6g\n", name,
                layout == Layout::Separate ? "separate" : "staggered", n, ns[samples / 2], ns[0],
                samples, sink);
}

}  // namespace

int main() {
    if (!check<double>("f64", 1e-14, 1e-14) || !check<float>("f32", 2e-6, 1e-6)) return 1;
    for (Layout layout : {Layout::Staggered, Layout::Separate}) {
        time_it<double>("f64", 1024, layout);
        time_it<float>("f32", 1024, layout);
    }
    return 0;
}
