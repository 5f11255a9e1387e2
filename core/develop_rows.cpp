#include "core/develop_rows.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include <xmmintrin.h>

#include "core/stages/print.h"
#include "core/simd.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

namespace {


// The input's sanitising and exposure below work on the lanes of a vector of any width
// (core/simd.h), one piece of code for the vector blocks and the scalar tails, so every
// machine gets the same exposures.

// NaN and -Inf are 0 (no light in their channel, not a layer driven to none by the mix);
// the rest is held within +-kMaxInput (floats or doubles).
template <typename V>
__attribute__((always_inline)) inline void sanitize_lanes(V& v) {
    using T = std::remove_reference_t<decltype(v[0])>;
    constexpr T max = T(kMaxInput);
    v = v > -std::numeric_limits<T>::infinity() ? v : V{};  // (false for NaN and -Inf alike: one compare)
    v = v < -max ? V{} - max : v;
    v = max < v ? V{} + max : v;
}

// Pixels' channels taken apart and put together in vector registers: each result is two
// shuffles of `vectors` (3 or 4) vectors of `lanes` floats, lane j first from v[0] and v[1]
// (low) or, for four, from v[2] and v[3] (high), then from those two (last) or, for three,
// from the first shuffle and v[2].
template <typename Picks, typename V, size_t... J>
__attribute__((always_inline)) inline V shuffled(const V* v, std::index_sequence<J...>) {
    const V low = __builtin_shufflevector(v[0], v[1], Picks::low(J)...);
    const V high = Picks::vectors == 4 ? __builtin_shufflevector(v[2], v[3], Picks::high(J)...) : v[2];
    return __builtin_shufflevector(low, high, Picks::last(J)...);
}

// Channel `channel` of pixels interleaved in `vectors` vectors (RGB: 3, RGBA: 4): lane j is
// float s = j vectors + channel of them.
template <int channel, int vectors_, int lanes>
struct Deinterleave {
    static constexpr int vectors = vectors_;
    static constexpr int source(int j) { return j * vectors + channel; }
    static constexpr int low(int j) { return source(j) < 2 * lanes ? source(j) : 0; }
    static constexpr int high(int j) { return source(j) >= 2 * lanes ? source(j) - 2 * lanes : 0; }
    static constexpr int last(int j) {
        if (vectors == 4) return source(j) < 2 * lanes ? j : lanes + j;
        return source(j) < 2 * lanes ? j : lanes + source(j) - 2 * lanes;
    }
};

// Vector k of `vectors` channel vectors interleaved: lane i is channel (k lanes + i) mod
// vectors of pixel (k lanes + i) / vectors.
template <int k, int vectors_, int lanes>
struct Interleave {
    static constexpr int vectors = vectors_;
    static constexpr int channel(int i) { return (k * lanes + i) % vectors; }
    static constexpr int pixel(int i) { return (k * lanes + i) / vectors; }
    static constexpr int low(int i) { return channel(i) < 2 ? channel(i) * lanes + pixel(i) : 0; }
    static constexpr int high(int i) { return channel(i) >= 2 ? (channel(i) - 2) * lanes + pixel(i) : 0; }
    static constexpr int last(int i) {
        if (vectors == 4) return channel(i) < 2 ? i : lanes + i;
        return channel(i) < 2 ? i : lanes + pixel(i);
    }
};

// The first `colours` (1 or 3) colour channels of the lanes' pixels from px on, `stride`
// floats apart (a grey image, grey_image, holds all three in its first): vector loads and
// shuffles for RGB and RGBA pixels, else a load a lane.
template <typename V>
__attribute__((always_inline)) inline void channels_at(const float* px, int stride, bool grey_image, int colours,
                                                       V* c) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    if constexpr (lanes >= 4) {
        if (colours == 3 && !grey_image && (stride == 3 || stride == 4)) {
            V v[4];
            for (int k = 0; k < stride; ++k) simd::load(v[k], px + k * lanes);
            const auto j = std::make_index_sequence<lanes>();
            if (stride == 3) {
                c[0] = shuffled<Deinterleave<0, 3, lanes>>(v, j), c[1] = shuffled<Deinterleave<1, 3, lanes>>(v, j),
                c[2] = shuffled<Deinterleave<2, 3, lanes>>(v, j);
            } else {
                c[0] = shuffled<Deinterleave<0, 4, lanes>>(v, j), c[1] = shuffled<Deinterleave<1, 4, lanes>>(v, j),
                c[2] = shuffled<Deinterleave<2, 4, lanes>>(v, j);
            }
            return;
        }
    }
    for (int i = 0; i < colours; ++i)
        for (int k = 0; k < lanes; ++k) c[i][k] = px[size_t(k) * stride + (grey_image ? 0 : i)];
}

// Each layer's exposure from the lanes' colours c: sanitised, then
// clamp((w . rgb) * scale, 0, kMaxInput), or for grey input (colours 1) clamp(grey * grey_scale).
template <typename V>
__attribute__((always_inline)) inline void layer_exposures(V* c, int colours, const float* weights,
                                                           const float* grey_scale, int layers, float scale, int x,
                                                           float* const* exposure) {
    constexpr float max = float(kMaxInput);
    for (int i = 0; i < colours; ++i) sanitize_lanes(c[i]);
    for (int l = 0; l < layers; ++l) {
        const float* w = weights + 3 * l;
        V e = colours == 1 ? c[0] * grey_scale[l] : (w[0] * c[0] + w[1] * c[1] + w[2] * c[2]) * scale;
        e = e < 0.0f ? V{} : e;  // a selection, as std::clamp: signed zeros kept
        e = max < e ? V{} + max : e;
        simd::store(exposure[l] + x, e);
    }
}

// Each layer's exposure at the lanes' pixels.
template <typename V>
__attribute__((always_inline)) inline void exposure_lanes(const float* px, int stride, bool grey_image, int colours,
                                                          const float* weights, const float* grey_scale, int layers,
                                                          float scale, int x, float* const* exposure) {
    V c[3]{};  // (only the first `colours` are read; zeroed so the compiler need not prove it)
    channels_at(px + size_t(x) * stride, stride, grey_image, colours, c);
    layer_exposures(c, colours, weights, grey_scale, layers, scale, x, exposure);
}

// Pixel k of the lanes' blocks of N pixels, from N vectors of the pixels in turn: lane j is
// pixel N j + k.
template <int N, int k, int lanes>
struct BlockPixel {
    static constexpr int vector(int j) { return (N * j + k) / lanes; }
    static constexpr int lane(int j) { return (N * j + k) % lanes; }
};

// sum, then + each block's pixel k of the row of N vectors v, k = 0 ... N - 1 (first: the
// sum starts at pixel 0).
template <int N, typename V, size_t... K>
__attribute__((always_inline)) inline void add_block_row(const V* v, bool first, V& sum, std::index_sequence<K...>) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    V pixel[N];
    (simd::picked<BlockPixel<N, int(K), lanes>, N>(v, pixel[K], std::make_index_sequence<lanes>()), ...);
    for (int k = 0; k < N; ++k) sum = first && k == 0 ? pixel[0] : sum + pixel[k];
}

// The mean colours of the lanes' whole NxN blocks (block_mean_row), their first pixels at
// `top` and the block's rows `row_step` floats apart, from N lanes of pixels of each row.
template <int N, typename V>
__attribute__((always_inline)) inline void block_mean_lanes(const float* top, std::ptrdiff_t row_step, int stride,
                                                            bool grey_image, int colours, V* c) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    for (int r = 0; r < N; ++r) {
        V row[3][N]{};  // per channel, the row's N vectors of pixels
        for (int q = 0; q < N; ++q) {
            V px[3]{};
            channels_at(top + r * row_step + std::ptrdiff_t(q * lanes) * stride, stride, grey_image, colours, px);
            for (int i = 0; i < colours; ++i) sanitize_lanes(px[i]), row[i][q] = px[i];
        }
        for (int i = 0; i < colours; ++i) add_block_row<N>(row[i], r == 0, c[i], std::make_index_sequence<N>());
    }
    for (int i = 0; i < colours; ++i) c[i] /= float(N * N);
}

// The first `colours` mean colours of proxy pixel (X, Y)'s block (as channels_at reads a
// pixel's), from what of it the image holds: any factor, a pixel at a time.
void edge_block_mean(const ConstImageView& in, const ProxyBlocks& blocks, int X, int Y, int colours, simd::Float1* c) {
    const int n = blocks.factor;
    const Window block = Window{n * X, n * Y, n * X + n, n * Y + n}.intersected(blocks.image);
    const bool grey_image = colour_channel_count(in) == 1;
    for (int y = block.y0; y < block.y1; ++y)
        for (int x = block.x0; x < block.x1; ++x) {
            simd::Float1 p[3]{};
            channels_at(in.at(x, y), int(in.pixel_stride), grey_image, colours, p);
            for (int i = 0; i < colours; ++i) {
                sanitize_lanes(p[i]);
                c[i] = x == block.x0 && y == block.y0 ? p[i] : c[i] + p[i];
            }
        }
    for (int i = 0; i < colours; ++i) c[i] /= float(block.pixel_count());
}

// The proxy pixels from X on of a row of whole blocks (top: the frame's first pixel of proxy
// pixel X's block, the block's rows row_step floats apart), each layer's exposure into
// exposure[layer] from x on.
template <int N, int lanes>
__attribute__((always_inline)) inline void block_exposure_row(const float* top, std::ptrdiff_t row_step, int stride,
                                                              bool grey_image, int colours, const float* weights,
                                                              const float* grey_scale, int layers, float scale, int x,
                                                              int width, float* const* exposure) {
    for (; x + lanes <= width; x += lanes) {
        const float* at = top + std::ptrdiff_t(N * x) * stride;
        for (int r = 0; r < N; ++r) simd::prefetch_ahead(at + r * row_step, N * lanes * stride * int(sizeof(float)));
        typename simd::Lanes<lanes>::F c[3]{};
        block_mean_lanes<N>(at, row_step, stride, grey_image, colours, c);
        layer_exposures(c, colours, weights, grey_scale, layers, scale, x, exposure);
    }
    for (; x < width; ++x) {
        simd::Float1 c[3]{};
        block_mean_lanes<N>(top + std::ptrdiff_t(N * x) * stride, row_step, stride, grey_image, colours, c);
        layer_exposures(c, colours, weights, grey_scale, layers, scale, x, exposure);
    }
}

template <int N>
struct BlockExposureRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* top, std::ptrdiff_t row_step, int stride,
                                                   bool grey_image, int colours, const float* weights,
                                                   const float* grey_scale, int layers, float scale, int x, int width,
                                                   float* const* exposure) {
        // (As ExposureRow: the common shapes with their sizes as constants.)
        if (colours == 3 && !grey_image && layers == 3 && stride == 3)
            block_exposure_row<N, lanes>(top, row_step, 3, false, 3, weights, grey_scale, 3, scale, x, width, exposure);
        else if (colours == 3 && !grey_image && layers == 3 && stride == 4)
            block_exposure_row<N, lanes>(top, row_step, 4, false, 3, weights, grey_scale, 3, scale, x, width, exposure);
        else
            block_exposure_row<N, lanes>(top, row_step, stride, grey_image, colours, weights, grey_scale, layers,
                                         scale, x, width, exposure);
    }
};

// Stores a vector of 4, 8 or 16 floats to p, 16-byte aligned, past the caches (a non-temporal
// store): the pass never reads the result back, and its cache line need not be read from
// memory before it is written (a frame's result is far larger than the caches). The
// intrinsics need their instruction set in the template's target, which it lacks: four or
// eight floats as SSE stores, which every set these kernels are compiled for has (a 32-byte
// one would need AVX); sixteen by clang's builtin, or for GCC the instruction itself (clang
// rejects a 512-bit asm operand outside an AVX-512 function).
template <typename V>
__attribute__((always_inline)) inline void stream_store(float* p, const V& v) {
    if constexpr (sizeof(V) == 16) {
        _mm_stream_ps(p, v);
    } else if constexpr (sizeof(V) == 32) {
        _mm_stream_ps(p, __builtin_shufflevector(v, v, 0, 1, 2, 3));
        _mm_stream_ps(p + 4, __builtin_shufflevector(v, v, 4, 5, 6, 7));
    } else {
        static_assert(sizeof(V) == 64, "a whole cache line");
#if defined(__clang__)
        __builtin_nontemporal_store(v, reinterpret_cast<V*>(p));
#else
        asm("vmovntps %1, %0" : "=m"(*reinterpret_cast<V*>(p)) : "v"(v));
#endif
    }
}

// Pixels x ... of the result's three rows into RGB (out_stride 3) or RGB and alpha (4, the
// alpha from the input's channel `alpha`, its pixels in_stride apart) in vector registers;
// other layouts a value at a time: the same values. `streaming`: RGB pixels stored past the
// caches (out_px + 3 x 16-byte aligned).
template <typename V, bool streaming = false>
__attribute__((always_inline)) inline void write_lanes(const float* const* result, const float* in_px, int in_stride,
                                                       int alpha, float* out_px, int out_stride, int x) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    V c[4]{};  // (c[3], the alpha, only where the input has one)
    for (int i = 0; i < 3; ++i) simd::load(c[i], result[i] + x);
    if (in_px)
        for (int k = 0; k < lanes; ++k) c[3][k] = in_px[size_t(x + k) * in_stride + alpha];
    float* out = out_px + size_t(x) * out_stride;
    if constexpr (lanes >= 4) {
        const auto i = std::make_index_sequence<lanes>();
        if (out_stride == 3 && !in_px) {
            auto put = [](float* p, const V& v) {
                if constexpr (streaming)
                    stream_store(p, v);
                else
                    simd::store(p, v);
            };
            put(out, shuffled<Interleave<0, 3, lanes>>(c, i));
            put(out + lanes, shuffled<Interleave<1, 3, lanes>>(c, i));
            put(out + 2 * lanes, shuffled<Interleave<2, 3, lanes>>(c, i));
            return;
        }
        if (out_stride == 4 && in_px) {
            simd::store(out, shuffled<Interleave<0, 4, lanes>>(c, i));
            simd::store(out + lanes, shuffled<Interleave<1, 4, lanes>>(c, i));
            simd::store(out + 2 * lanes, shuffled<Interleave<2, 4, lanes>>(c, i));
            simd::store(out + 3 * lanes, shuffled<Interleave<3, 4, lanes>>(c, i));
            return;
        }
    }
    for (int k = 0; k < lanes; ++k) {
        for (int i = 0; i < 3; ++i) out[size_t(k) * out_stride + i] = c[i][k];
        if (in_px) out[size_t(k) * out_stride + 3] = c[3][k];
    }
}

struct WriteRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* const* result, const float* in_px, int in_stride,
                                                   int alpha, float* out_px, int out_stride, int width) {
        int x = 0;
        // RGB pixels: from the first whose address is 64-byte aligned on, streamed, each 16 pixels
        // three whole lines (the same values; with AVX-512 3-4 % of a 4K frame's time; with AVX2
        // on a Zen 3, two threads, the write 4.9-5.6 -> 3.5-5.3 ms).
        if (out_stride == 3 && !in_px && width >= 4 * lanes) {
            const uintptr_t offset = reinterpret_cast<uintptr_t>(out_px) % 64;  // (a float's: a multiple of 4)
            const int head = int((64 - offset) / 4 % 16 * 11 % 16);  // 3 head = (64 - offset) / 4 mod 16
            for (; x < head; ++x) write_lanes<simd::Float1>(result, in_px, in_stride, alpha, out_px, out_stride, x);
            for (; x + lanes <= width; x += lanes)
                write_lanes<typename simd::Lanes<lanes>::F, true>(result, in_px, in_stride, alpha, out_px, 3, x);
            _mm_sfence();  // (ordered before whatever reads the result)
        }
        for (; x + lanes <= width; x += lanes) {
            simd::prefetch_ahead<true>(out_px + size_t(x) * out_stride, lanes * out_stride * int(sizeof(float)));
            write_lanes<typename simd::Lanes<lanes>::F>(result, in_px, in_stride, alpha, out_px, out_stride, x);
        }
        for (; x < width; ++x) write_lanes<simd::Float1>(result, in_px, in_stride, alpha, out_px, out_stride, x);
    }
};

template <int lanes>
__attribute__((always_inline)) inline void exposure_row(const float* px, int stride, bool grey_image, int colours,
                                                        const float* weights, const float* grey_scale, int layers,
                                                        float scale, int width, float* const* exposure) {
    int x = 0;
    for (; x + lanes <= width; x += lanes) {
        simd::prefetch_ahead(px + size_t(x) * stride, lanes * stride * int(sizeof(float)));
        exposure_lanes<typename simd::Lanes<lanes>::F>(px, stride, grey_image, colours, weights, grey_scale, layers,
                                                       scale, x, exposure);
    }
    for (; x < width; ++x)
        exposure_lanes<simd::Float1>(px, stride, grey_image, colours, weights, grey_scale, layers, scale, x, exposure);
}

struct ExposureRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* px, int stride, bool grey_image, int colours,
                                                   const float* weights, const float* grey_scale, int layers,
                                                   float scale, int width, float* const* exposure) {
        // RGB or RGBA pixels onto three layers, the common shapes, with their sizes as
        // constants (the other shapes' branches gone, the loops unrolled); the same operations.
        if (colours == 3 && !grey_image && layers == 3 && stride == 3)
            exposure_row<lanes>(px, 3, false, 3, weights, grey_scale, 3, scale, width, exposure);
        else if (colours == 3 && !grey_image && layers == 3 && stride == 4)
            exposure_row<lanes>(px, 4, false, 3, weights, grey_scale, 3, scale, width, exposure);
        else
            exposure_row<lanes>(px, stride, grey_image, colours, weights, grey_scale, layers, scale, width, exposure);
    }
};

}  // namespace

int colour_channel(const ConstImageView& in, int c) { return colour_channel_count(in) == 3 ? c : 0; }

double sanitize(float v) {
    simd::Double1 lane{double(v)};
    sanitize_lanes(lane);
    return lane[0];
}

// The proxy columns of row Y from X0 on whose blocks the image holds whole, at a factor
// with vector code: [first, last), or none (first = last).
static void whole_blocks(const ProxyBlocks& blocks, int Y, int X0, int width, int& first, int& last) {
    const int n = blocks.factor;
    const Window& image = blocks.image;
    const bool all_rows = n * Y >= image.y0 && n * Y + n <= image.y1 && n <= kMaxVectorProxyFactor;
    first = std::clamp(ceil_div(image.x0, n), X0, X0 + width);
    last = all_rows ? std::clamp(floor_div(image.x1, n), first, X0 + width) : first;
}

void block_mean_row(const ConstImageView& in, const ProxyBlocks& blocks, int Y, int X0, int width, float* colours) {
    int first, last;
    whole_blocks(blocks, Y, X0, width, first, last);
    const int n = colour_channel_count(in);
    for (int X = X0; X < X0 + width; ++X) {
        simd::Float1 c[3]{};
        const bool whole = X >= first && X < last &&
                           with_vector_factor(blocks.factor, [&](auto N) {
                               block_mean_lanes<decltype(N)::value>(in.at(N * X, N * Y), in.row_stride, int(in.pixel_stride), n == 1,
                                                   n, c);
                           });
        if (!whole) edge_block_mean(in, blocks, X, Y, n, c);
        for (int i = 0; i < n; ++i) colours[size_t(X - X0) * n + i] = c[i][0];
    }
}

FilmExposure::FilmExposure(const ConstImageView& in, const std::vector<std::array<double, 3>>& weights,
                           bool grey_input, double scale, const ProxyBlocks* blocks_of)
    : in_(in), layers_(int(weights.size())), colours_(grey_input ? 1 : 3), scale_(float(scale)), blocks_of_(blocks_of) {
    for (const auto& w : weights) {
        for (double v : w) weights_.push_back(float(v));
        grey_scale_.push_back(float((w[0] + w[1] + w[2]) * scale));
    }
}

void FilmExposure::row(int y, int x0, int width, float* const* exposure) const {
    const bool grey_image = colour_channel_count(in_) == 1;
    if (!blocks_of_) {
        simd::dispatch<ExposureRow>(in_.at(x0, y), int(in_.pixel_stride), grey_image, colours_, weights_.data(),
                                    grey_scale_.data(), layers_, scale_, width, exposure);
        return;
    }
    // The blocks the image holds whole in vectors (from the row's first pixel: the rows as
    // the kernel indexes them from x0), the partial ones at its edges one at a time.
    int first, last;
    whole_blocks(*blocks_of_, y, x0, width, first, last);
    auto edge = [&](int X) {
        simd::Float1 c[3]{};
        edge_block_mean(in_, *blocks_of_, X, y, colours_, c);
        layer_exposures(c, colours_, weights_.data(), grey_scale_.data(), layers_, scale_, X - x0, exposure);
    };
    for (int X = x0; X < first; ++X) edge(X);
    if (first < last) {
        float* from_first[3];
        for (int l = 0; l < layers_; ++l) from_first[l] = exposure[l] + (first - x0);
        with_vector_factor(blocks_of_->factor, [&](auto N) {
            simd::dispatch<BlockExposureRow<decltype(N)::value>>(in_.at(N * first, N * y), in_.row_stride, int(in_.pixel_stride),
                                                grey_image, colours_, weights_.data(), grey_scale_.data(), layers_,
                                                scale_, 0, last - first, static_cast<float* const*>(from_first));
        });
    }
    for (int X = last; X < x0 + width; ++X) edge(X);
}

void convert_row(OutputMode output, double base_density, float* row, int width) {
    for (int x = 0; x < width; ++x) {
        if (output == OutputMode::negative)
            row[x] = float(std::pow(10.0, -double(row[x])));
        else if (output == OutputMode::scan)
            row[x] = float(scan_level(double(row[x]), base_density));
    }
}

void write_row(const float* const* result, size_t planes, const ConstImageView& in, const ImageView& out, int y, int x0,
               int width) {
    const int alpha = colour_channel_count(in);  // the channel after the colour
    const bool copy_alpha = alpha < in.channels && out.channels >= 4;
    const float* rows[3];
    for (size_t c = 0; c < 3; ++c) rows[c] = result[std::min(c, planes - 1)];
    simd::dispatch<WriteRow>(rows, copy_alpha ? in.at(x0, y) : nullptr, int(in.pixel_stride), alpha, out.at(x0, y),
                             int(out.pixel_stride), width);
}

}  // namespace darkroom
