// Image views and windows in absolute frame coordinates.
//
// Conventions for all of core/:
// - Pixels are float. A view does not own memory: it is a pointer plus strides, so an OFX
//   host's buffer or an OIIO ImageBuf can be processed without copies.
// - Every view knows where it sits in the full frame: `window.x0, window.y0` are the
//   absolute coordinates of its first pixel. Grain, edges and filters are defined on
//   absolute coordinates, which is what makes a tile or render window equal that window
//   of a full-frame render, bit for bit.
// - Strides are in floats, so negative (bottom-up) row strides are allowed.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>
#include <memory>
#include <new>
#include <utility>
#include <vector>

#include "core/plane_memory.h"

namespace darkroom {

// Floor and ceiling of v / n, and v's remainder in [0, n), for n > 0 and any sign of v: the
// block of pixel v among blocks of n pixels from 0, and row v's slot in a ring of n rows.
inline int floor_div(int v, int n) { return v >= 0 ? v / n : -((-v + n - 1) / n); }
inline int ceil_div(int v, int n) { return -floor_div(-v, n); }
inline int floor_mod(int v, int n) { return ((v % n) + n) % n; }

// A rectangle of pixels in absolute frame coordinates; x1, y1 are exclusive.
struct Window {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;

    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
    bool empty() const { return x1 <= x0 || y1 <= y0; }
    long long pixel_count() const { return empty() ? 0 : (long long)width() * height(); }
    bool contains(const Window& o) const {
        return o.empty() || (o.x0 >= x0 && o.y0 >= y0 && o.x1 <= x1 && o.y1 <= y1);
    }
    Window grown(int halo_px) const { return {x0 - halo_px, y0 - halo_px, x1 + halo_px, y1 + halo_px}; }
    Window moved(int dx, int dy) const { return {x0 + dx, y0 + dy, x1 + dx, y1 + dy}; }
    Window intersected(const Window& o) const {
        return {std::max(x0, o.x0), std::max(y0, o.y0), std::min(x1, o.x1), std::min(y1, o.y1)};
    }
    bool operator==(const Window& o) const { return x0 == o.x0 && y0 == o.y0 && x1 == o.x1 && y1 == o.y1; }
};

// How many of an image's first channels are colour: grey (1 channel) or grey and alpha (2)
// hold one, RGB (3) and RGB with alpha and more (4+) three; the channel after them is alpha.
inline int colour_channel_count(int channels) { return channels >= 3 ? 3 : 1; }

// Colour premultiplied by an alpha, divided by it where it is above 0 (at 0 there is no
// coverage to divide out), and multiplied back: the plugin's and the program's, one code.
// The alpha counts as a coverage in [0, 1]: beyond it, its nearest end; NaN, 0 (no light),
// so a bad alpha never makes the colour non-finite.
inline float coverage(float alpha) { return alpha > 0 ? (alpha < 1 ? alpha : 1.0f) : 0.0f; }
inline void unpremultiply(float* pixel, int colour_channels, float alpha) {
    const float a = coverage(alpha);
    if (a > 0)
        for (int c = 0; c < colour_channels; ++c) pixel[c] /= a;
}
inline void premultiply(float* pixel, int colour_channels, float alpha) {
    const float a = coverage(alpha);
    for (int c = 0; c < colour_channels; ++c) pixel[c] *= a;
}

template <typename T>
struct BasicImageView {
    T* data = nullptr;          // first pixel, i.e. (window.x0, window.y0)
    Window window;              // where the pixels sit in the frame
    int channels = 0;
    std::ptrdiff_t pixel_stride = 0;  // floats between horizontally adjacent pixels
    std::ptrdiff_t row_stride = 0;    // floats between vertically adjacent pixels
    // How many of the first channels are colour, 1 (grey) or 3 (RGB); 0: by the channel
    // count (colour_channel_count). A file's channel names can say otherwise: a grey plate
    // with alpha and depth (Y, A, Z) has one.
    int colour_channels = 0;

    // A view of mutable pixels is also a view of constant ones.
    operator BasicImageView<const T>() const { return {data, window, channels, pixel_stride, row_stride, colour_channels}; }

    // Pointer to pixel (x, y) in absolute coordinates.
    T* at(int x, int y) const {
        return data + (std::ptrdiff_t)(y - window.y0) * row_stride + (std::ptrdiff_t)(x - window.x0) * pixel_stride;
    }
};
using ImageView = BasicImageView<float>;
using ConstImageView = BasicImageView<const float>;

// How many of a view's first channels are colour; the channel after them is alpha.
inline int colour_channel_count(const ConstImageView& view) {
    return view.colour_channels > 0 ? view.colour_channels : colour_channel_count(view.channels);
}

// Storage whose resize() leaves new floats unset: a stage that writes every pixel of its
// output plane need not pay for zeroing it first (about a copy pass per plane). Large
// blocks are recycled (core/plane_memory.h). All are 64-byte aligned: the streams' rings
// keep rows a whole number of cache lines apart, so that a vector of a row loads from one
// line, not two.
template <typename T>
struct UnsetAllocator : std::allocator<T> {
    template <typename U>
    struct rebind {
        using other = UnsetAllocator<U>;
    };
    UnsetAllocator() = default;
    template <typename U>
    UnsetAllocator(const UnsetAllocator<U>&) noexcept {}
    T* allocate(size_t n) {
        if (n > std::numeric_limits<size_t>::max() / sizeof(T)) throw std::bad_array_new_length();
        if (n * sizeof(T) < kPooledBytes) return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t{64}));
        return static_cast<T*>(take_plane_memory(n * sizeof(T)));
    }
    void deallocate(T* p, size_t n) noexcept {
        if (n * sizeof(T) < kPooledBytes)
            ::operator delete(p, std::align_val_t{64});
        else
            give_plane_memory(p, n * sizeof(T));
    }
    template <typename U>
    void construct(U* p) noexcept {
        ::new (static_cast<void*>(p)) U;
    }
    template <typename U, typename... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

// A single-channel float image that owns its pixels: the working buffer between stages.
struct Plane {
    Window window;
    std::vector<float, UnsetAllocator<float>> pixels;

    Plane() = default;
    explicit Plane(const Window& w, float fill = 0.0f)
        : window(w), pixels((size_t)std::max<long long>(w.pixel_count(), 0), fill) {}
    // A plane whose every pixel the caller writes before reading any.
    static Plane unset(const Window& w) {
        Plane p;
        p.window = w;
        p.pixels.resize((size_t)std::max<long long>(w.pixel_count(), 0));
        return p;
    }
    float& at(int x, int y) { return pixels[(size_t)(y - window.y0) * window.width() + (x - window.x0)]; }
    float at(int x, int y) const { return pixels[(size_t)(y - window.y0) * window.width() + (x - window.x0)]; }
    float* row(int y) { return pixels.data() + (size_t)(y - window.y0) * window.width(); }
    const float* row(int y) const { return pixels.data() + (size_t)(y - window.y0) * window.width(); }
};

// An interleaved float image that owns its pixels (tests, the CLI, synthetic scenes).
struct Image {
    Window window;
    int channels = 0;
    std::vector<float> pixels;

    Image() = default;
    Image(const Window& w, int nchannels, float fill = 0.0f)
        : window(w), channels(nchannels), pixels((size_t)std::max<long long>(w.pixel_count(), 0) * nchannels, fill) {}
    Image(int width, int height, int nchannels, float fill = 0.0f) : Image(Window{0, 0, width, height}, nchannels, fill) {}

    ImageView view() {
        return {pixels.data(), window, channels, channels, (std::ptrdiff_t)channels * window.width()};
    }
    ConstImageView view() const {
        return {pixels.data(), window, channels, channels, (std::ptrdiff_t)channels * window.width()};
    }
    float* at(int x, int y) { return view().at(x, y); }
    const float* at(int x, int y) const { return view().at(x, y); }
};

}  // namespace darkroom
