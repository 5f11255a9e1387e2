#include "core/demo_scene.h"

#include <cmath>

namespace darkroom {

namespace {

// ColorChecker Classic in 8-bit sRGB as published by X-Rite for the post-2009 chart,
// row by row (dark skin ... black).
constexpr unsigned char kColorChecker[24][3] = {
    {115, 82, 68},   {194, 150, 130}, {98, 122, 157},  {87, 108, 67},   {133, 128, 177}, {103, 189, 170},
    {214, 126, 44},  {80, 91, 166},   {193, 90, 99},   {94, 60, 108},   {157, 188, 64},  {224, 163, 46},
    {56, 61, 150},   {70, 148, 73},   {175, 54, 60},   {231, 199, 31},  {187, 86, 149},  {8, 133, 161},
    {243, 243, 242}, {200, 200, 200}, {160, 160, 160}, {122, 122, 121}, {85, 85, 85},    {52, 52, 52}};

// The sRGB decoding function (IEC 61966-2-1).
double srgb_to_linear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

void fill(Image& img, int x, int y, float r, float g, float b) {
    float* p = img.at(x, y);
    p[0] = r, p[1] = g, p[2] = b;
}

}  // namespace

Image demo_scene(int width, int height) {
    Image img(width, height, 3, 0.18f);
    const int band = height / 4;
    for (int y = 0; y < band; ++y)  // grey ramp
        for (int x = 0; x < width; ++x) {
            float v = float(0.18 * std::exp2(-8.0 + 12.0 * (x + 0.5) / width));
            fill(img, x, y, v, v, v);
        }
    for (int y = band; y < 2 * band; ++y)  // step wedge
        for (int x = 0; x < width; ++x) {
            int step = x * 21 / width;
            float v = float(0.18 * std::exp2(-5.0 + 0.5 * step));
            fill(img, x, y, v, v, v);
        }
    for (int y = 2 * band; y < 3 * band; ++y)  // sine bursts (left) and a Siemens star (right)
        for (int x = 0; x < width; ++x) {
            double v;
            if (x < width / 2) {
                int burst = x * 6 / (width / 2);
                double period_px = 32.0 / std::exp2(burst);  // 32 px down to 1 px
                v = 0.18 * (1.0 + 0.8 * std::sin(2 * M_PI * x / period_px));
            } else {
                double cx = width * 0.75, cy = 2.5 * band;
                double angle = std::atan2(y - cy, x - cx);
                v = std::sin(36.0 * angle) > 0 ? 0.9 : 0.03;
            }
            fill(img, x, y, float(v), float(v), float(v));
        }
    for (int y = 3 * band; y < height; ++y)  // colour chart, 6 x 4 patches
        for (int x = 0; x < width; ++x) {
            int col = x * 6 / width, row = (y - 3 * band) * 4 / (height - 3 * band);
            const unsigned char* c = kColorChecker[row * 6 + col];
            fill(img, x, y, float(srgb_to_linear(c[0] / 255.0)), float(srgb_to_linear(c[1] / 255.0)),
                 float(srgb_to_linear(c[2] / 255.0)));
        }
    return img;
}

}  // namespace darkroom
