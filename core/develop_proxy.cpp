// The preview tier's proxy (QualityTier::proxy_scale): the frame rendered at twice the pixel
// pitch, so that grain, MTF and halation keep their size on the film, and upsampled to the
// frame's pixels. Every proxy pixel is a fixed 2x2 block of the film frame's pixels (the
// proxy grid starts at the film frame's origin), so any window, tile or thread count reads
// the same proxy pixels and gives the same output pixels as the whole frame.
#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/develop.h"
#include "core/develop_rows.h"
#include "core/parallel.h"

namespace darkroom {

namespace {

constexpr int kScale = 2;  // the proxy's pixel pitch over the frame's

int floor_div(int v) { return v >= 0 ? v / kScale : -((-v + kScale - 1) / kScale); }
int ceil_div(int v) { return -floor_div(-v); }

// The proxy pixels that hold the frame's pixels of `w`.
Window proxy_cover(const Window& w) { return {floor_div(w.x0), floor_div(w.y0), ceil_div(w.x1), ceil_div(w.y1)}; }

// The frame's pixels a proxy window covers.
Window frame_cover(const Window& w) { return {w.x0 * kScale, w.y0 * kScale, w.x1 * kScale, w.y1 * kScale}; }

// Bilinear interpolation of the proxy at a frame pixel's centre: frame pixel 2X + 0.5 lies
// at proxy coordinate X - 0.25, so an even pixel takes 3/4 of proxy pixel X and 1/4 of X - 1,
// an odd one 3/4 of X and 1/4 of X + 1; at the proxy frame's edges the edge pixel repeats.
struct Taps {
    int near, far;
};
Taps taps(int x, int lo, int hi) {
    const int X = floor_div(x);
    const int other = x - X * kScale == 0 ? X - 1 : X + 1;
    return {std::clamp(X, lo, hi - 1), std::clamp(other, lo, hi - 1)};
}

// An input value as the film sees it (develop_rows.h, sanitize): NaN and -Inf no light, the
// rest held within +-kMaxInput.
inline float film_value(float v) {
    constexpr float max = float(kMaxInput);
    return v > -std::numeric_limits<float>::infinity() ? std::clamp(v, -max, max) : 0.0f;
}

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
    const Window proxy_out = proxy_window(out_window);
    const Window proxy_in = proxy_->input_window(proxy_out);
    // Down: each proxy pixel the mean of the frame pixels of its block that the image holds,
    // as the film sees them (NaN as no light), so an image's edge block is its own pixels'.
    auto start = std::chrono::steady_clock::now();
    const int colours = colour_channel_count(in);
    UnsetImage small(proxy_in, colours);
    parallel_for(proxy_in.y0, proxy_in.y1, threads, [&](int y0, int y1) {
        for (int Y = y0; Y < y1; ++Y) {
            const Window rows = frame_cover({proxy_in.x0, Y, proxy_in.x1, Y + 1}).intersected(frame_);
            const float* first = in.at(rows.x0, rows.y0);
            const float* second = rows.height() == 2 ? in.at(rows.x0, rows.y0 + 1) : nullptr;
            float* px = small.view.at(proxy_in.x0, Y);
            for (int X = proxy_in.x0; X < proxy_in.x1; ++X, px += colours) {
                const int x0 = std::max(X * kScale, frame_.x0), x1 = std::min(X * kScale + kScale, frame_.x1);
                const std::ptrdiff_t at = (x0 - rows.x0) * in.pixel_stride;
                const std::ptrdiff_t next = x1 - x0 == 2 ? in.pixel_stride : -1;  // (-1: no second column)
                // 1, 2 or 4 pixels: the reciprocal is exact, so this is the sum over the count.
                const float share = 1.0f / float((x1 - x0) * rows.height());
                for (int c = 0; c < colours; ++c) {
                    float sum = film_value(first[at + c]);
                    if (next > 0) sum += film_value(first[at + next + c]);
                    if (second) {
                        sum += film_value(second[at + c]);
                        if (next > 0) sum += film_value(second[at + next + c]);
                    }
                    px[c] = sum * share;
                }
            }
        }
    });
    add_time(times, "downsample", start);

    UnsetImage result(proxy_out, 3);  // (the proxy's run writes every pixel of it)
    proxy_->run(small.view, result.view, threads, times);

    // Up: bilinear, along x then y (each proxy row along x once); the input's alpha (the channel after its colour) copied
    // at the frame's pixels, as the other tiers do.
    start = std::chrono::steady_clock::now();
    const Window& pf = proxy_->frame_;
    const bool copy_alpha = colours < in.channels && out.channels >= 4;
    std::vector<Taps> columns;
    for (int x = out_window.x0; x < out_window.x1; ++x) columns.push_back(taps(x, pf.x0, pf.x1));
    const int width = out_window.width();
    parallel_for(out_window.y0, out_window.y1, threads, [&](int band_y0, int band_y1) {
        // In bands of rows, each proxy row a band reads upsampled along x once (a row serves
        // up to four).
        constexpr int kRows = 32;
        std::vector<float> along_x(size_t(kRows / 2 + 3) * size_t(width) * 3);
        for (int y0 = band_y0; y0 < band_y1; y0 += kRows) {
            const int y1 = std::min(band_y1, y0 + kRows);
            const Taps top = taps(y0, pf.y0, pf.y1), bottom = taps(y1 - 1, pf.y0, pf.y1);
            const int first = std::min(top.near, top.far), last = std::max(bottom.near, bottom.far);
            for (int Y = first; Y <= last; ++Y) {
                const float* row = result.view.at(proxy_out.x0, Y);
                float* wide = &along_x[size_t(Y - first) * size_t(width) * 3];
                for (int i = 0; i < width; ++i) {
                    const int n = (columns[size_t(i)].near - proxy_out.x0) * 3;
                    const int f = (columns[size_t(i)].far - proxy_out.x0) * 3;
                    for (int c = 0; c < 3; ++c) wide[3 * i + c] = 0.75f * row[n + c] + 0.25f * row[f + c];
                }
            }
            for (int y = y0; y < y1; ++y) {
                const Taps ty = taps(y, pf.y0, pf.y1);
                const float* near = &along_x[size_t(ty.near - first) * size_t(width) * 3];
                const float* far = &along_x[size_t(ty.far - first) * size_t(width) * 3];
                float* px = out.at(out_window.x0, y);
                if (out.pixel_stride == 3) {
                    for (int i = 0; i < 3 * width; ++i) px[i] = 0.75f * near[i] + 0.25f * far[i];
                    continue;
                }
                for (int i = 0; i < width; ++i, px += out.pixel_stride) {
                    for (int c = 0; c < 3; ++c) px[c] = 0.75f * near[3 * i + c] + 0.25f * far[3 * i + c];
                    if (copy_alpha) px[3] = in.at(out_window.x0 + i, y)[colours];
                }
            }
        }
    });
    add_time(times, "upsample", start);
}

}  // namespace darkroom
