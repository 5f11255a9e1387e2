// The preview tier's proxy (quality.h, proxy_factor): the frame rendered at N times the pixel
// pitch, so that grain, MTF and halation keep their size on the film, and upsampled to the
// frame's pixels. Every proxy pixel is a fixed NxN block of the film frame's pixels (the
// proxy grid starts at the film frame's origin, and N depends on the film frame alone), so
// any window, tile or thread count reads the same proxy pixels and gives the same output
// pixels as the whole frame.
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

// The proxy pixels that hold the frame's pixels of `w`.
Window proxy_cover(const Window& w, int factor) {
    return {floor_div(w.x0, factor), floor_div(w.y0, factor), ceil_div(w.x1, factor), ceil_div(w.y1, factor)};
}

// Bilinear interpolation of the proxy at a frame pixel's centre (develop_rows.h,
// proxy_upsample_offset): frame pixel x takes `near_weight` of its block's proxy pixel and
// `far_weight` of the neighbour on the side of its centre; at the proxy frame's edges the
// edge pixel repeats. Along x, then y.
struct Taps {
    int near, far;
    float near_weight, far_weight;
};
Taps taps(int x, int factor, int lo, int hi) {
    const int X = floor_div(x, factor), k = x - factor * X;
    const int other = proxy_upsample_offset(k, factor) < 0 ? X - 1 : X + 1;
    const float far = proxy_upsample_far_weight(k, factor);
    return {std::clamp(X, lo, hi - 1), std::clamp(other, lo, hi - 1), 1.0f - far, far};
}

// One row of the proxy along x: proxy pixels X + from ... X + n - 1 of `row` (one channel,
// pixels X - 1 and X + n there too) into frame pixels N (X + from) ... N (X + n) - 1 of `wide`
// (from its start at frame pixel N X), a pixel at a time for any factor N.
void along_x_pixels(const float* row, float* wide, int from, int n, int factor) {
    for (int i = from; i < n; ++i)
        for (int k = 0; k < factor; ++k) {
            const float far = proxy_upsample_far_weight(k, factor);
            const float side = row[proxy_upsample_offset(k, factor) < 0 ? i - 1 : i + 1];
            wide[size_t(factor) * size_t(i) + size_t(k)] = (1.0f - far) * row[i] + far * side;
        }
}

// Frame pixel q lanes + j of the lanes' proxy pixels' N frame pixels each (pixel[k] holding
// their pixel k): lane j of output vector q.
template <int N, int q, int lanes>
struct FramePixel {
    static constexpr int vector(int j) { return (q * lanes + j) % N; }
    static constexpr int lane(int j) { return (q * lanes + j) / N; }
};

// along_x_pixels from proxy pixel 0 on, N a factor with vector code: a vector of proxy pixels
// at a time, its N frame pixels each interleaved into N vectors.
template <int N>
struct AlongX {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* row, float* wide, int n) {
        using V = typename simd::Lanes<lanes>::F;
        int i = 0;
        for (; i + lanes <= n; i += lanes) {
            V left, centre, right;
            simd::load(left, row + i - 1), simd::load(centre, row + i), simd::load(right, row + i + 1);
            V pixel[N];
            for (int k = 0; k < N; ++k) {
                const float far = proxy_upsample_far_weight(k, N);
                pixel[k] = (1.0f - far) * centre + far * (proxy_upsample_offset(k, N) < 0 ? left : right);
            }
            store_interleaved(pixel, wide + size_t(N) * size_t(i), std::make_index_sequence<N>());
        }
        along_x_pixels(row, wide, i, n, N);
    }
    template <typename V, size_t... Q>
    __attribute__((always_inline)) static void store_interleaved(const V* pixel, float* wide,
                                                                 std::index_sequence<Q...>) {
        constexpr int lanes = sizeof(V) / sizeof(float);
        V out[N];
        (simd::picked<FramePixel<N, int(Q), lanes>, N>(pixel, out[Q], std::make_index_sequence<lanes>()), ...);
        for (int q = 0; q < N; ++q) simd::store(wide + q * lanes, out[q]);
    }
};

// Along y: near_weight of the nearer row and far_weight of the farther, `n` values.
struct AlongY {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* near, const float* far, float near_weight,
                                                   float far_weight, float* out, int n) {
        using V = typename simd::Lanes<lanes>::F;
        int i = 0;
        for (; i + lanes <= n; i += lanes) {
            V a, b;
            simd::load(a, near + i), simd::load(b, far + i);
            simd::store(out + i, near_weight * a + far_weight * b);
        }
        for (; i < n; ++i) out[i] = near_weight * near[i] + far_weight * far[i];
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

double proxy_upsampled_sigma_ratio(double lag1_correlation, int factor) {
    // Along one axis frame pixel N X + k is (1 - w) a + w b of two neighbours (w its far
    // weight): variance (1 - w)^2 + w^2 + 2 w (1 - w) rho of theirs. The two axes multiply
    // (the correlation separable), so the mean variance over the frame's pixels is the square
    // of the mean over k, and its square root that mean.
    double mean = 0;
    for (int k = 0; k < factor; ++k) {
        const double w = proxy_upsample_far_weight(k, factor);
        mean += (1 - w) * (1 - w) + w * w + 2 * w * (1 - w) * lag1_correlation;
    }
    return mean / factor;
}

int proxy_factor(const QualityTier& tier, const FrameGeometry& frame) {
    return proxy_factor(tier, frame.film_width_px(), frame.film_height_px());
}

FrameGeometry proxy_geometry(const FrameGeometry& frame, int factor) {
    const Window image =
        proxy_cover({frame.x0, frame.y0, frame.x0 + frame.width, frame.y0 + frame.height}, factor);
    FrameGeometry proxy = frame;
    proxy.x0 = image.x0, proxy.y0 = image.y0;
    proxy.width = image.width(), proxy.height = image.height();
    proxy.film_width = ceil_div(frame.film_width_px(), factor);
    proxy.film_height = ceil_div(frame.film_height_px(), factor);
    return proxy;
}

void upsample_proxy(const ConstImageView& proxy, const Window& proxy_frame, int factor, const ConstImageView& in,
                    const ImageView& out, const Window& out_window, int threads) {
    // Each proxy row a band reads along x once, into the frame's columns from the first of
    // the block at out_window's first, each channel a row (and a pixel past each end, the
    // edge repeated, for the taps at the proxy frame's edges); each output row then along y
    // and written as the other tiers write, the input's alpha copied.
    const Window& proxy_out = proxy.window;
    const int X0 = floor_div(out_window.x0, factor), X1 = ceil_div(out_window.x1, factor), n = X1 - X0;
    const int skip = out_window.x0 - factor * X0;  // (0 ... factor - 1 columns)
    parallel_for(out_window.y0, out_window.y1, threads, [&](int band_y0, int band_y1) {
        // The proxy rows along x, in a ring of four slots by row (an output row reads its
        // nearer row and the one above or below).
        constexpr int kSlots = 4;
        const size_t wide_size = size_t(factor) * size_t(n);
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
                    const float* row = proxy.at(proxy_out.x0, Y) + c;
                    auto at = [&](int X) { return row[proxy.pixel_stride * (X - proxy_out.x0)]; };
                    auto column = [&](int X) -> float& { return padded[size_t(X - X0 + 1)]; };
                    for (int X = first; X <= last; ++X) column(X) = at(X);
                    for (int X = X0 - 1; X < first; ++X) column(X) = at(first);
                    for (int X = last + 1; X <= X1; ++X) column(X) = at(last);
                    const float* proxy_row = &padded[1];
                    float* frame_row = into + c * wide_size;
                    const bool vector = with_vector_factor(factor, [&](auto N) {
                        simd::dispatch<AlongX<decltype(N)::value>>(proxy_row, frame_row, n);
                    });
                    if (!vector) along_x_pixels(proxy_row, frame_row, 0, n, factor);
                }
            }
            return into;
        };
        for (int y = band_y0; y < band_y1; ++y) {
            const Taps ty = taps(y, factor, proxy_frame.y0, proxy_frame.y1);
            const float* near = along_x(ty.near);
            const float* far = along_x(ty.far);
            simd::dispatch<AlongY>(near, far, ty.near_weight, ty.far_weight, rows.data(), int(3 * wide_size));
            const float* planes[3] = {&rows[size_t(skip)], &rows[wide_size + size_t(skip)],
                                      &rows[2 * wide_size + size_t(skip)]};
            write_row(planes, 3, in, out, y, out_window.x0, out_window.width());
        }
    });
}

Window Plan::proxy_window(const Window& output) const {
    const Window cover = proxy_cover(output, proxy_factor_);
    return Window{cover.x0 - 1, cover.y0 - 1, cover.x1 + 1, cover.y1 + 1}.intersected(proxy_->frame_);
}

void Plan::run_proxy(const ConstImageView& in, const ImageView& out, const Window& out_window, int threads,
                     StageTimes* times) const {
    // Down: the proxy's exposure reads the frame's pixels in blocks as it goes; a run stage
    // after stage reads them from an image of the proxy's pixels instead, the same values.
    const int factor = proxy_factor_;
    const ProxyBlocks blocks{frame_, factor};
    const Window proxy_out = proxy_window(out_window);
    UnsetImage result(proxy_out, 3);  // (the proxy's run writes every pixel of it)
    if (proxy_->runs_in_one_pass()) {
        proxy_->run_one_pass(in, result.view, proxy_out, threads, times, &blocks);
    } else {
        const auto start = std::chrono::steady_clock::now();
        const Window proxy_in = proxy_->input_window(proxy_out);
        UnsetImage small(proxy_in, colour_channel_count(in));
        parallel_for(proxy_in.y0, proxy_in.y1, threads, [&](int y0, int y1) {
            for (int Y = y0; Y < y1; ++Y)
                block_mean_row(in, blocks, Y, proxy_in.x0, proxy_in.width(), small.view.at(proxy_in.x0, Y));
        });
        add_time(times, "downsample", start);
        proxy_->run(small.view, result.view, threads, times);
    }

    // Up.
    const auto start = std::chrono::steady_clock::now();
    upsample_proxy(result.view, proxy_->frame_, factor, in, out, out_window, threads);
    add_time(times, "upsample", start);
}

}  // namespace darkroom
