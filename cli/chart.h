// Line charts for reports: a title, two axes with ticks and labels (linear or log), and
// named series in colours, drawn as SVG text or as a raster image through OpenImageIO.
// Several charts (panels) can share one picture, side by side.
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace darkroom::cli {

struct ChartSeries {
    std::string name;
    std::vector<double> x, y;  // points in order; non-finite points (and <= 0 on a log axis) break the line
    std::array<float, 3> colour{0.f, 0.f, 0.f};  // linear-ish 0..1 RGB; use chart_colour()
    bool dashed = false;
};

struct ChartAxis {
    std::string label;
    bool log = false;
    double min = NAN, max = NAN;  // NAN: from the data
};

struct Chart {
    std::string title;
    ChartAxis x, y;
    std::vector<ChartSeries> series;
};

// A palette of distinguishable colours; channel names R, G, B get red, green and blue.
std::array<float, 3> chart_colour(int index);
std::array<float, 3> channel_colour(const std::string& channel_name, int index);

std::string charts_to_svg(const std::vector<Chart>& panels);

// Writes the panels side by side: SVG for a .svg path, otherwise a raster image in the
// format OpenImageIO picks by the extension (e.g. .png), written atomically. Raster text
// needs a font; without one the chart is drawn without text and `text_drawn` says so.
void write_charts(const std::string& path, const std::vector<Chart>& panels, bool* text_drawn = nullptr);

}  // namespace darkroom::cli
