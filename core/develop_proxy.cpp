// The preview tier's proxy (QualityTier::proxy_scale): the frame rendered at twice the pixel
// pitch, so that grain, MTF and halation keep their size on the film, and upsampled to the
// frame's pixels. Every proxy pixel is a fixed 2x2 block of the film frame's pixels (the
// proxy grid starts at the film frame's origin), so any window, tile or thread count reads
// the same proxy pixels and gives the same output pixels as the whole frame.
#include <algorithm>
#include <chrono>
#include <climits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/develop.h"
#include "core/develop_rows.h"
#include "core/parallel.h"
#include "core/simd.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

namespace {

constexpr int kScale = 2;  // the proxy's pixel pitch over the frame's

int floor_div(int v) { return v >= 0 ? v / kScale : -((-v + kScale - 1) / kScale); }
int ceil_div(int v) { return -floor_div(-v); }

// The proxy pixels that hold the frame's pixels of `w`.
Window proxy_cover(const Window& w) { return {floor_div(w.x0), floor_div(w.y0), ceil_div(w.x1), ceil_div(w.y1)}; }

// Bilinear interpolation of the proxy at a frame pixel's centre: frame pixel 2X + 0.5 lies
// at proxy coordinate X - 0.25, so an even pixel takes 3/4 of proxy pixel X and 1/4 of X - 1,
// an odd one 3/4 of X and 1/4 of X + 1; at the proxy frame's edges the edge pixel repeats.
// Along x, then y.
struct Taps {
    int near, far;
};
Taps taps(int x, int lo, int hi) {
    const int X = floor_div(x);
    const int other = x - X * kScale == 0 ? X - 1 : X + 1;
    return {std::clamp(X, lo, hi - 1), std::clamp(other, lo, hi - 1)};
}

// One row of the proxy along x: proxy pixels X ... X + n - 1 of `row` (one channel, pixels X - 1
// and X + n there too) into frame pixels 2X ... 2X + 2n - 1 of `wide`.
struct AlongX {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* row, float* wide, int n) {
        using V = typename simd::Lanes<lanes>::F;
        int i = 0;
        for (; i + lanes <= n; i += lanes) {
            V left, centre, right;
            simd::load(left, row + i - 1), simd::load(centre, row + i), simd::load(right, row + i + 1);
            const V even = 0.75f * centre + 0.25f * left, odd = 0.75f * centre + 0.25f * right;
            V first, second;
            zip(even, odd, first, second, std::make_index_sequence<lanes>());
            simd::store(wide + 2 * i, first), simd::store(wide + 2 * i + lanes, second);
        }
        for (; i < n; ++i) {
            wide[2 * i] = 0.75f * row[i] + 0.25f * row[i - 1];
            wide[2 * i + 1] = 0.75f * row[i] + 0.25f * row[i + 1];
        }
    }
    // The lanes of a and b alternately: the first half's into `first`, the second's into `second`.
    template <typename V, size_t... J>
    __attribute__((always_inline)) static void zip(const V& a, const V& b, V& first, V& second,
                                                   std::index_sequence<J...>) {
        constexpr int lanes = sizeof...(J);
        first = __builtin_shufflevector(a, b, int(J / 2 + J % 2 * lanes)...);
        second = __builtin_shufflevector(a, b, int((J + lanes) / 2 + J % 2 * lanes)...);
    }
};

// Along y: 3/4 of the nearer row and 1/4 of the farther, `n` values.
struct AlongY {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* near, const float* far, float* out, int n) {
        using V = typename simd::Lanes<lanes>::F;
        int i = 0;
        for (; i + lanes <= n; i += lanes) {
            V a, b;
            simd::load(a, near + i), simd::load(b, far + i);
            simd::store(out + i, 0.75f * a + 0.25f * b);
        }
        for (; i < n; ++i) out[i] = 0.75f * near[i] + 0.25f * far[i];
    }
};

// An interleaved image whose pixels come recycled and unset, as a Plane's (image.h): a 4K
// frame's proxy is 26 MB, which fresh pages would fault in zeroed at every run.
struct UnsetImage {
    std::vector<float, UnsetAllocator<float>> pixels;
    ImageView view;
    UnsetImage(const Window& w, int channels) {
        pixels.resize(size_t(std::max<long long>(w.pixel_count(), 0)) * size_t(channels));
        view = {pixels.data(), w, channels, channels, std::ptrdiff_t(channels) * w.width()};
    }
};

void add_time(StageTimes* times, const char* stage, std::chrono::steady_clock::time_point since) {
    if (times) times->add(stage, std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count());
}

}  // namespace

double proxy_upsampled_sigma_ratio(double lag1_correlation) {
    // Along one axis a frame pixel is 3/4 a + 1/4 b of two neighbours: variance
    // (9/16 + 1/16 + 2 (3/16) rho) of theirs. The two axes multiply, and so does the square root.
    return 0.625 + 0.375 * lag1_correlation;
}

FrameGeometry proxy_geometry(const FrameGeometry& frame) {
    const Window image = proxy_cover({frame.x0, frame.y0, frame.x0 + frame.width, frame.y0 + frame.height});
    FrameGeometry proxy = frame;
    proxy.x0 = image.x0, proxy.y0 = image.y0;
    proxy.width = image.width(), proxy.height = image.height();
    proxy.film_width = ceil_div(frame.film_width_px());
    return proxy;
}

Window Plan::proxy_window(const Window& output) const {
    const Window cover = proxy_cover(output);
    return Window{cover.x0 - 1, cover.y0 - 1, cover.x1 + 1, cover.y1 + 1}.intersected(proxy_->frame_);
}

void Plan::run_proxy(const ConstImageView& in, const ImageView& out, const Window& out_window, int threads,
                     StageTimes* times) const {
    // Down: the proxy's exposure reads the frame's pixels in 2x2 blocks as it goes; a run
    // stage after stage reads them from an image of the proxy's pixels instead, the same values.
    const Window proxy_out = proxy_window(out_window);
    UnsetImage result(proxy_out, 3);  // (the proxy's run writes every pixel of it)
    if (proxy_->runs_in_one_pass()) {
        proxy_->run_one_pass(in, result.view, proxy_out, threads, times, &frame_);
    } else {
        const auto start = std::chrono::steady_clock::now();
        const Window proxy_in = proxy_->input_window(proxy_out);
        UnsetImage small(proxy_in, colour_channel_count(in));
        parallel_for(proxy_in.y0, proxy_in.y1, threads, [&](int y0, int y1) {
            for (int Y = y0; Y < y1; ++Y)
                block_mean_row(in, frame_, Y, proxy_in.x0, proxy_in.width(), small.view.at(proxy_in.x0, Y));
        });
        add_time(times, "downsample", start);
        proxy_->run(small.view, result.view, threads, times);
    }

    // Up: each proxy row a band reads along x once, into the frame's columns from the even one
    // at or before out_window's first, each channel a row (and a pixel past each end, the edge
    // repeated, for the taps at the proxy frame's edges); each output row then along y and
    // written as the other tiers write, the input's alpha copied.
    const auto start = std::chrono::steady_clock::now();
    const Window& pf = proxy_->frame_;
    const int X0 = floor_div(out_window.x0), X1 = ceil_div(out_window.x1), n = X1 - X0;
    const int skip = out_window.x0 - kScale * X0;  // (0 or 1 column)
    parallel_for(out_window.y0, out_window.y1, threads, [&](int band_y0, int band_y1) {
        // The proxy rows along x, in a ring of four slots by row (an output row reads its
        // nearer row and the one above or below).
        constexpr int kSlots = 4;
        const size_t wide_size = size_t(kScale) * size_t(n);
        std::vector<float> padded(size_t(n) + 2), wide(kSlots * 3 * wide_size), rows(3 * wide_size);
        int held[kSlots] = {INT_MIN, INT_MIN, INT_MIN, INT_MIN};
        auto along_x = [&](int Y) {
            const int slot = ((Y % kSlots) + kSlots) % kSlots;
            float* into = &wide[size_t(slot) * 3 * wide_size];
            if (held[slot] != Y) {
                held[slot] = Y;
                // (The columns past the proxy's are at the proxy frame's edges: the edge repeats.)
                const int first = std::max(X0 - 1, proxy_out.x0), last = std::min(X1, proxy_out.x1 - 1);
                for (int c = 0; c < 3; ++c) {
                    const float* row = result.view.at(proxy_out.x0, Y) + c;
                    auto at = [&](int X) { return row[3 * (X - proxy_out.x0)]; };
                    auto column = [&](int X) -> float& { return padded[size_t(X - X0 + 1)]; };
                    for (int X = first; X <= last; ++X) column(X) = at(X);
                    for (int X = X0 - 1; X < first; ++X) column(X) = at(first);
                    for (int X = last + 1; X <= X1; ++X) column(X) = at(last);
                    simd::dispatch<AlongX>(static_cast<const float*>(&padded[1]), into + c * wide_size, n);
                }
            }
            return into;
        };
        for (int y = band_y0; y < band_y1; ++y) {
            const Taps ty = taps(y, pf.y0, pf.y1);
            const float* near = along_x(ty.near);
            const float* far = along_x(ty.far);
            simd::dispatch<AlongY>(near, far, rows.data(), int(3 * wide_size));
            const float* planes[3] = {&rows[size_t(skip)], &rows[wide_size + size_t(skip)],
                                      &rows[2 * wide_size + size_t(skip)]};
            write_row(planes, 3, in, out, y, out_window.x0, out_window.width());
        }
    });
    add_time(times, "upsample", start);
}

}  // namespace darkroom
