#include "cli/chart.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <algorithm>
#include <filesystem>
#include <sstream>

#include "cli/atomic_file.h"
#include "cli/image_io.h"

namespace darkroom::cli {

namespace {

constexpr int kPanelWidth = 640, kPanelHeight = 440;
constexpr int kLeft = 80, kRight = 24, kTop = 56, kBottom = 56;  // plot area margins, px
constexpr int kFontPx = 14;

std::string format_number(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", v);
    return text;
}

struct Range {
    double lo, hi;
};

Range data_range(const Chart& chart, bool x_axis) {
    const ChartAxis& axis = x_axis ? chart.x : chart.y;
    double lo = INFINITY, hi = -INFINITY;
    for (const ChartSeries& s : chart.series)
        for (double v : x_axis ? s.x : s.y)
            if (std::isfinite(v) && (!axis.log || v > 0)) lo = std::min(lo, v), hi = std::max(hi, v);
    if (!std::isfinite(lo)) lo = axis.log ? 1 : 0, hi = axis.log ? 10 : 1;
    if (hi <= lo) {
        if (axis.log) lo /= 2, hi *= 2;
        else lo -= 0.5 * std::max(1e-12, std::abs(lo)), hi += 0.5 * std::max(1e-12, std::abs(hi));
    }
    if (!axis.log && !x_axis) {  // room above and below the curves
        double pad = 0.05 * (hi - lo);
        lo -= pad, hi += pad;
    }
    if (std::isfinite(axis.min)) lo = axis.min;
    if (std::isfinite(axis.max)) hi = axis.max;
    return {lo, hi};
}

std::vector<double> ticks(Range r, bool log) {
    std::vector<double> out;
    if (log) {
        int d0 = (int)std::floor(std::log10(r.lo)), d1 = (int)std::ceil(std::log10(r.hi));
        const std::vector<double> steps = d1 - d0 <= 2 ? std::vector<double>{1, 2, 5} : std::vector<double>{1};
        for (int d = d0; d <= d1; ++d)
            for (double m : steps) {
                double v = m * std::pow(10.0, d);
                if (v >= r.lo * (1 - 1e-9) && v <= r.hi * (1 + 1e-9)) out.push_back(v);
            }
        return out;
    }
    double raw = (r.hi - r.lo) / 5, magnitude = std::pow(10.0, std::floor(std::log10(raw))), step = magnitude;
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * magnitude >= raw) {
            step = m * magnitude;
            break;
        }
    for (double v = std::ceil(r.lo / step) * step; v <= r.hi + 1e-9 * step; v += step)
        out.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
    return out;
}

// What a chart is drawn with: pixels in a picture, y down.
struct Canvas {
    virtual ~Canvas() = default;
    virtual void line(double x0, double y0, double x1, double y1, const std::array<float, 3>& colour, bool dashed,
                      double width) = 0;
    enum class Align { left, centre, right };
    virtual void text(double x, double y, const std::string& s, Align align, int size) = 0;
};

void draw_chart(Canvas& canvas, const Chart& chart, int x_offset) {
    const Range xr = data_range(chart, true), yr = data_range(chart, false);
    const double left = x_offset + kLeft, right = x_offset + kPanelWidth - kRight, top = kTop,
                 bottom = kPanelHeight - kBottom;
    auto map = [](double v, Range r, bool log, double a, double b) {
        double t = log ? (std::log10(v) - std::log10(r.lo)) / (std::log10(r.hi) - std::log10(r.lo))
                       : (v - r.lo) / (r.hi - r.lo);
        return a + t * (b - a);
    };
    auto px = [&](double v) { return map(v, xr, chart.x.log, left, right); };
    auto py = [&](double v) { return map(v, yr, chart.y.log, bottom, top); };
    const std::array<float, 3> ink{0.f, 0.f, 0.f}, grid{0.85f, 0.85f, 0.85f};

    for (double t : ticks(xr, chart.x.log)) {
        canvas.line(px(t), top, px(t), bottom, grid, false, 1);
        canvas.line(px(t), bottom, px(t), bottom + 5, ink, false, 1);
        canvas.text(px(t), bottom + 8 + kFontPx, format_number(t), Canvas::Align::centre, kFontPx);
    }
    for (double t : ticks(yr, chart.y.log)) {
        canvas.line(left, py(t), right, py(t), grid, false, 1);
        canvas.line(left - 5, py(t), left, py(t), ink, false, 1);
        canvas.text(left - 8, py(t) + kFontPx / 3, format_number(t), Canvas::Align::right, kFontPx);
    }
    canvas.line(left, top, left, bottom, ink, false, 1);
    canvas.line(left, bottom, right, bottom, ink, false, 1);
    canvas.line(left, top, right, top, ink, false, 1);
    canvas.line(right, top, right, bottom, ink, false, 1);
    canvas.text((left + right) / 2, 24, chart.title, Canvas::Align::centre, kFontPx + 4);
    canvas.text((left + right) / 2, kPanelHeight - 12, chart.x.label, Canvas::Align::centre, kFontPx);
    canvas.text(x_offset + 8, top - 10, chart.y.label, Canvas::Align::left, kFontPx);

    auto usable = [&](double x, double y) {
        return std::isfinite(x) && std::isfinite(y) && (!chart.x.log || x > 0) && (!chart.y.log || y > 0) &&
               x >= std::min(xr.lo, xr.hi) && x <= std::max(xr.lo, xr.hi) && y >= std::min(yr.lo, yr.hi) &&
               y <= std::max(yr.lo, yr.hi);
    };
    for (size_t k = 0; k < chart.series.size(); ++k) {
        const ChartSeries& s = chart.series[k];
        for (size_t i = 1; i < std::min(s.x.size(), s.y.size()); ++i)
            if (usable(s.x[i - 1], s.y[i - 1]) && usable(s.x[i], s.y[i]))
                canvas.line(px(s.x[i - 1]), py(s.y[i - 1]), px(s.x[i]), py(s.y[i]), s.colour, s.dashed, 2);
        // Legend, top right inside the plot.
        double ly = top + 16 + 18 * k;
        canvas.line(right - 150, ly - 4, right - 120, ly - 4, s.colour, s.dashed, 2);
        canvas.text(right - 114, ly, s.name, Canvas::Align::left, kFontPx - 2);
    }
}

std::string escape_xml(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '&') out += "&amp;";
        else if (c == '<') out += "&lt;";
        else if (c == '>') out += "&gt;";
        else if (c == '"') out += "&quot;";
        else out += c;
    }
    return out;
}

struct SvgCanvas : Canvas {
    std::ostringstream body;
    void line(double x0, double y0, double x1, double y1, const std::array<float, 3>& c, bool dashed,
              double width) override {
        body << "<line x1=\"" << x0 << "\" y1=\"" << y0 << "\" x2=\"" << x1 << "\" y2=\"" << y1
             << "\" stroke=\"rgb(" << int(255 * c[0] + 0.5) << "," << int(255 * c[1] + 0.5) << ","
             << int(255 * c[2] + 0.5) << ")\" stroke-width=\"" << width << "\""
             << (dashed ? " stroke-dasharray=\"6,4\"" : "") << "/>\n";
    }
    void text(double x, double y, const std::string& s, Align align, int size) override {
        const char* anchor = align == Align::left ? "start" : align == Align::centre ? "middle" : "end";
        body << "<text x=\"" << x << "\" y=\"" << y << "\" font-family=\"sans-serif\" font-size=\"" << size
             << "\" text-anchor=\"" << anchor << "\">" << escape_xml(s) << "</text>\n";
    }
};

struct RasterCanvas : Canvas {
    OIIO::ImageBuf picture;
    bool has_font = false;  // without one, no text
    std::string font;       // "" is OIIO's default font
    double dash_phase = 0;

    void line(double x0, double y0, double x1, double y1, const std::array<float, 3>& c, bool dashed,
              double width) override {
        double length = std::hypot(x1 - x0, y1 - y0);
        const double on = 6, period = 10;
        // Dashes continue across the segments of a polyline.
        int pieces = dashed ? std::max(1, (int)std::ceil(length)) : 1;
        for (int i = 0; i < pieces; ++i) {
            double a = double(i) / pieces, b = double(i + 1) / pieces;
            if (dashed && std::fmod(dash_phase + a * length, period) >= on) continue;
            for (int offset = 0; offset < (int)width; ++offset)
                OIIO::ImageBufAlgo::render_line(picture, (int)std::lround(x0 + a * (x1 - x0)),
                                                (int)std::lround(y0 + a * (y1 - y0)) + offset,
                                                (int)std::lround(x0 + b * (x1 - x0)),
                                                (int)std::lround(y0 + b * (y1 - y0)) + offset, c);
        }
        if (dashed) dash_phase = std::fmod(dash_phase + length, period);
    }
    void text(double x, double y, const std::string& s, Align align, int size) override {
        if (!has_font || s.empty()) return;
        const float black[3] = {0.f, 0.f, 0.f};
        auto alignx = align == Align::left     ? OIIO::ImageBufAlgo::TextAlignX::Left
                      : align == Align::centre ? OIIO::ImageBufAlgo::TextAlignX::Center
                                               : OIIO::ImageBufAlgo::TextAlignX::Right;
        OIIO::ImageBufAlgo::render_text(picture, (int)std::lround(x), (int)std::lround(y), s, size, font, black,
                                        alignx);
    }
};

// OIIO's default font if it has one, else DejaVu Sans (Debian's fonts-dejavu-core).
bool find_font(std::string& font) {
    OIIO::ImageBuf probe(OIIO::ImageSpec(64, 32, 3, OIIO::TypeDesc::FLOAT));
    const float black[3] = {0.f, 0.f, 0.f};
    for (const char* name : {"", "DejaVuSans", "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"})
        if (OIIO::ImageBufAlgo::render_text(probe, 2, 20, "0", kFontPx, name, black)) {
            font = name;
            return true;
        }
    return false;
}

}  // namespace

std::array<float, 3> chart_colour(int index) {
    static const std::array<float, 3> palette[] = {{0.84f, 0.15f, 0.16f}, {0.17f, 0.63f, 0.17f}, {0.12f, 0.47f, 0.71f},
                                                   {1.0f, 0.5f, 0.05f},   {0.58f, 0.4f, 0.74f},  {0.55f, 0.34f, 0.29f},
                                                   {0.89f, 0.47f, 0.76f}, {0.5f, 0.5f, 0.5f}};
    return palette[((index % 8) + 8) % 8];
}

std::array<float, 3> channel_colour(const std::string& name, int index) {
    if (name == "R" || name == "r") return chart_colour(0);
    if (name == "G" || name == "g") return chart_colour(1);
    if (name == "B" || name == "b") return chart_colour(2);
    return chart_colour(index);
}

std::string charts_to_svg(const std::vector<Chart>& panels) {
    SvgCanvas canvas;
    for (size_t i = 0; i < panels.size(); ++i) draw_chart(canvas, panels[i], (int)i * kPanelWidth);
    std::ostringstream svg;
    const int width = (int)std::max<size_t>(1, panels.size()) * kPanelWidth;
    svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << kPanelHeight
        << "\" viewBox=\"0 0 " << width << " " << kPanelHeight << "\">\n"
        << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
        << canvas.body.str() << "</svg>\n";
    return svg.str();
}

void write_charts(const std::string& path, const std::vector<Chart>& panels, bool* text_drawn) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower((unsigned char)c));
    if (ext == ".svg") {
        write_text_atomically(path, charts_to_svg(panels));
        if (text_drawn) *text_drawn = true;
        return;
    }
    RasterCanvas canvas;
    const int width = (int)std::max<size_t>(1, panels.size()) * kPanelWidth;
    canvas.picture.reset(OIIO::ImageSpec(width, kPanelHeight, 3, OIIO::TypeDesc::FLOAT));
    const float white[3] = {1.f, 1.f, 1.f};
    OIIO::ImageBufAlgo::fill(canvas.picture, white);
    canvas.has_font = find_font(canvas.font);
    for (size_t i = 0; i < panels.size(); ++i) draw_chart(canvas, panels[i], (int)i * kPanelWidth);
    if (text_drawn) *text_drawn = canvas.has_font;
    Image image(width, kPanelHeight, 3);
    canvas.picture.get_pixels(canvas.picture.roi(), OIIO::TypeDesc::FLOAT, image.pixels.data());
    write_image(path, image, OIIO::ImageSpec(width, kPanelHeight, 3, OIIO::TypeDesc::FLOAT));
}

}  // namespace darkroom::cli
