#include "ocio/lut_bake.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace darkroom::ocio {

namespace {

namespace fs = std::filesystem;

const double kLn2 = std::log(2.0);

std::string format_number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

void validate(const LutBakeSettings& s, LutFormat format) {
    if (s.cube_size < 2 || s.cube_size > 129)
        throw OcioError("LUT cube size " + std::to_string(s.cube_size) + " is outside 2..129 (the OCIO 2.1 limit)");
    if (format == LutFormat::cube && s.input == LutInput::scene_linear &&
        (s.cube_shaper_size < 2 || s.cube_shaper_size > 65536))
        throw OcioError("LUT shaper size " + std::to_string(s.cube_shaper_size) + " is outside 2..65536");
    const LogShaper& sh = s.shaper;
    if (s.input == LutInput::scene_linear &&
        !(std::isfinite(sh.mid_grey) && sh.mid_grey > 0 && std::isfinite(sh.stops_below) && sh.stops_below >= 0 &&
          std::isfinite(sh.stops_above) && sh.stops_above >= 0 && sh.stops_below + sh.stops_above > 0 &&
          sh.stops_below + sh.stops_above <= 64))
        throw OcioError("LUT shaper range (grey " + format_number(sh.mid_grey) + ", -" + format_number(sh.stops_below) +
                        " .. +" + format_number(sh.stops_above) +
                        " stops) must have grey > 0 and 0 < total stops <= 64");
}

// The .cube shaper as OCIO's Resolve reader applies it: linear interpolation between
// `table` entries sampled evenly over 0..lin_max.
struct SampledShaper {
    std::vector<float> table;

    // The input whose interpolated shaper value is s (table is increasing).
    double inverse(double s, double lin_max) const {
        const double step = lin_max / double(table.size() - 1);
        s = std::clamp(s, (double)table.front(), (double)table.back());
        const auto above = std::upper_bound(table.begin(), table.end(), (float)s);
        std::size_t i = (std::size_t)std::max<std::ptrdiff_t>(0, (above - table.begin()) - 1);
        i = std::min(i, table.size() - 2);
        const double t = (s - table[i]) / double(table[i + 1] - table[i]);
        return (double(i) + std::clamp(t, 0.0, 1.0)) * step;
    }
};

SampledShaper sample_shaper(const LogShaper& shaper, int size) {
    SampledShaper sampled;
    sampled.table.resize((std::size_t)size);
    const double lin_max = shaper.lin_max();
    for (int i = 0; i < size; ++i)
        sampled.table[(std::size_t)i] = (float)shaper.to_shaper(lin_max * i / double(size - 1));
    return sampled;
}

// Lattice inputs, red fastest (the order of .cube files), axes[c] the coordinates along c.
std::vector<float> lattice_inputs(int n, const std::array<std::vector<double>, 3>& axes) {
    std::vector<float> rgb((std::size_t)n * n * n * 3);
    std::size_t p = 0;
    for (int b = 0; b < n; ++b)
        for (int g = 0; g < n; ++g)
            for (int r = 0; r < n; ++r, p += 3) {
                rgb[p] = (float)axes[0][(std::size_t)r];
                rgb[p + 1] = (float)axes[1][(std::size_t)g];
                rgb[p + 2] = (float)axes[2][(std::size_t)b];
            }
    return rgb;
}

void check_finite(const std::vector<float>& out, const std::vector<float>& in) {
    for (std::size_t i = 0; i < out.size(); ++i)
        if (!std::isfinite(out[i])) {
            const std::size_t p = i - i % 3;
            throw OcioError("the look gave a non-finite value for input (" + format_number(in[p]) + ", " +
                            format_number(in[p + 1]) + ", " + format_number(in[p + 2]) + "); nothing was written");
        }
}

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);)
        if (!line.empty()) lines.push_back(line);
    return lines;
}

void append_triplet(std::string& out, float r, float g, float b) {
    char buf[64];
    const int n = std::snprintf(buf, sizeof buf, "%.7g %.7g %.7g\n", r, g, b);
    out.append(buf, (std::size_t)n);
}

std::string cube_text(const LutBakeSettings& s, const std::string& summary, const SampledShaper* shaper,
                      const std::vector<float>& lattice) {
    std::string out;
    out.reserve(lattice.size() * 12 + (shaper ? shaper->table.size() * 30 : 0) + 1024);
    // The Resolve reader takes comments only before the header, and no TITLE.
    for (const std::string& line : lines_of(s.title)) out += "# " + line + "\n";
    for (const std::string& line : lines_of(s.description)) out += "# " + line + "\n";
    out += "# " + summary + "\n";
    if (shaper) {
        out += "LUT_1D_SIZE " + std::to_string(shaper->table.size()) + "\n";
        char range[64];
        std::snprintf(range, sizeof range, "LUT_1D_INPUT_RANGE 0 %.9g\n", s.shaper.lin_max());
        out += range;
    }
    out += "LUT_3D_SIZE " + std::to_string(s.cube_size) + "\n";
    if (shaper) {
        char buf[48];
        for (float v : shaper->table) {
            // Nine digits: the reader gets back exactly the floats the lattice was placed by.
            const int n = std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", v, v, v);
            out.append(buf, (std::size_t)n);
        }
    }
    for (std::size_t p = 0; p < lattice.size(); p += 3) append_triplet(out, lattice[p], lattice[p + 1], lattice[p + 2]);
    return out;
}

void append_operations(OCIO::GroupTransform& group, const OCIO::ConstGroupTransformRcPtr& operations) {
    if (operations)
        for (int i = 0; i < operations->getNumTransforms(); ++i)
            group.appendTransform(operations->getTransform(i)->createEditableCopy());
}

// A CLF's process list: its name, description and summary, and the input operations.
OCIO::GroupTransformRcPtr clf_group(const LutBakeSettings& s, const std::string& summary) {
    OCIO::GroupTransformRcPtr group = OCIO::GroupTransform::Create();
    OCIO::FormatMetadata& meta = group->getFormatMetadata();
    meta.setID("darkroom-look");
    std::string name = s.title.empty() ? "Darkroom look" : s.title;
    std::replace(name.begin(), name.end(), '\n', ' ');
    meta.setName(name.c_str());
    for (const std::string& line : lines_of(s.description))
        meta.addChildElement(OCIO::METADATA_DESCRIPTION, line.c_str());
    meta.addChildElement(OCIO::METADATA_DESCRIPTION, summary.c_str());
    append_operations(*group, s.clf_prefix);
    return group;
}

std::string clf_written(const OCIO::GroupTransform& group) {
    std::ostringstream out;
    group.write(OCIO::Config::CreateRaw(), "Academy/ASC Common LUT Format", out);
    return out.str();
}

// A tetrahedral LUT3D of a lattice in the order lattice_inputs gives.
OCIO::Lut3DTransformRcPtr lut3d_of(int size, const std::vector<float>& lattice) {
    const unsigned long n = (unsigned long)size;
    OCIO::Lut3DTransformRcPtr lut = OCIO::Lut3DTransform::Create(n);
    lut->setInterpolation(OCIO::INTERP_TETRAHEDRAL);
    lut->setFileOutputBitDepth(OCIO::BIT_DEPTH_F32);
    std::size_t p = 0;
    for (unsigned long b = 0; b < n; ++b)
        for (unsigned long g = 0; g < n; ++g)
            for (unsigned long r = 0; r < n; ++r, p += 3)
                lut->setValue(r, g, b, lattice[p], lattice[p + 1], lattice[p + 2]);
    return lut;
}

std::string clf_text(const LutBakeSettings& s, const std::string& summary, const std::vector<float>& lattice) {
    OCIO::GroupTransformRcPtr group = clf_group(s, summary);
    if (s.input == LutInput::scene_linear) {
        // s = k log2(x / x_lo) + k / ln 2 above x_lo; OCIO's linear segment below the
        // break is the tangent there, which is the shaper's toe.
        const double x_lo = s.shaper.toe_break(), k = s.shaper.slope();
        OCIO::LogCameraTransformRcPtr log = OCIO::LogCameraTransform::Create({x_lo, x_lo, x_lo});
        log->setBase(2.0);
        log->setLogSideSlopeValue({k, k, k});
        log->setLogSideOffsetValue({k / kLn2, k / kLn2, k / kLn2});
        log->setLinSideSlopeValue({1.0 / x_lo, 1.0 / x_lo, 1.0 / x_lo});
        log->setLinSideOffsetValue({0.0, 0.0, 0.0});
        group->appendTransform(log);
    }
    group->appendTransform(lut3d_of(s.cube_size, lattice));
    return clf_written(*group);
}

// What the .clf's input operations are, for its summary.
std::string prefix_summary(const LutBakeSettings& s) {
    if (!s.clf_prefix) return {};
    return "; before it, the exact conversion from the file's input colour space (" +
           std::to_string(s.clf_prefix->getNumTransforms()) + " OCIO operations)";
}

}  // namespace

// ---- LogShaper ----

double LogShaper::toe_break() const { return mid_grey * std::exp2(-stops_below); }
double LogShaper::lin_max() const { return mid_grey * std::exp2(stops_above); }
double LogShaper::slope() const { return 1.0 / (stops_below + stops_above + 1.0 / kLn2); }

double LogShaper::to_shaper(double x) const {
    const double x_lo = toe_break(), k = slope();
    if (x >= x_lo) return k * (std::log2(x / x_lo) + 1.0 / kLn2);
    return k * x / (x_lo * kLn2);
}

double LogShaper::from_shaper(double s) const {
    const double x_lo = toe_break(), k = slope();
    if (s >= k / kLn2) return x_lo * std::exp2(s / k - 1.0 / kLn2);
    return s * x_lo * kLn2 / k;
}

// ---- Baking ----

LutFormat lut_format_for_path(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = (char)std::tolower((unsigned char)c);
    if (ext == ".cube") return LutFormat::cube;
    if (ext == ".clf") return LutFormat::clf;
    throw OcioError("cannot tell the LUT format of '" + path + "': use a .cube or .clf file name");
}

BakedLut bake_lut(const PixelFunction& look, const LutBakeSettings& settings, LutFormat format) {
    BakedLut baked;
    baked.format = format;
    validate(settings, baked.format);
    if (settings.clf_prefix && baked.format != LutFormat::clf)
        throw std::invalid_argument("darkroom::ocio::bake_lut: only a .clf can hold input operations");
    const int n = settings.cube_size;
    const bool shaped = settings.input == LutInput::scene_linear;

    // Where the lattice points sit in input units, per axis.
    std::vector<double> axis((std::size_t)n);
    SampledShaper sampled;
    if (shaped && baked.format == LutFormat::cube) sampled = sample_shaper(settings.shaper, settings.cube_shaper_size);
    for (int i = 0; i < n; ++i) {
        const double s = i / double(n - 1);
        if (!shaped)
            axis[(std::size_t)i] = s;
        else if (baked.format == LutFormat::cube)
            axis[(std::size_t)i] = sampled.inverse(s, settings.shaper.lin_max());
        else
            axis[(std::size_t)i] = settings.shaper.from_shaper(s);
    }

    const std::vector<float> inputs = lattice_inputs(n, {axis, axis, axis});
    std::vector<float> lattice = inputs;
    look(lattice.data(), lattice.size() / 3);
    check_finite(lattice, inputs);

    const std::string size = std::to_string(n);
    std::string summary = "Darkroom: 3D LUT " + size + "x" + size + "x" + size + " (tetrahedral)";
    if (shaped) {
        const LogShaper& sh = settings.shaper;
        summary += " after a log2 shaper";
        if (baked.format == LutFormat::cube)
            summary += " (sampled at " + std::to_string(settings.cube_shaper_size) + " points)";
        summary += ": scene-linear input 0 .. " + format_number(sh.lin_max()) + ", evenly spaced in stops from " +
                   format_number(sh.toe_break()) + " (grey " + format_number(sh.mid_grey) + " -" +
                   format_number(sh.stops_below) + " stops) to +" + format_number(sh.stops_above) +
                   " stops, linear below; inputs below 0 or above " + format_number(sh.lin_max()) + " clamp";
    } else {
        summary += ": encoded input 0 .. 1, inputs outside clamp";
    }
    summary += prefix_summary(settings);
    baked.summary = summary;

    baked.text = baked.format == LutFormat::cube ? cube_text(settings, summary, shaped ? &sampled : nullptr, lattice)
                                                 : clf_text(settings, summary, lattice);
    return baked;
}

namespace {

// The conversion's operations, if OCIO can write them to a CLF exactly; else null.
OCIO::ConstGroupTransformRcPtr clf_writable_operations(const OCIO::Processor& processor) {
    try {
        OCIO::ConstGroupTransformRcPtr ops =
            processor.getOptimizedProcessor(OCIO::OPTIMIZATION_LOSSLESS)->createGroupTransform();
        std::ostringstream probe;
        ops->write(OCIO::Config::CreateRaw(), "Academy/ASC Common LUT Format", probe);
        return ops;
    } catch (const OCIO::Exception&) {
        return nullptr;
    }
}

template <typename T>
T named(T transform, const std::string& name) {
    transform->getFormatMetadata().setName(name.c_str());
    return transform;
}

// The .clf of a layered look (LayeredLook) after settings.clf_prefix, and `output` after it.
BakedLut bake_layered(const LayeredLook& look, const LutBakeSettings& settings,
                      const OCIO::ConstGroupTransformRcPtr& output) {
    LutBakeSettings sized = settings;
    if (look.table && look.table_size != 0) sized.cube_size = look.table_size;
    validate(sized, LutFormat::clf);
    const double lo = look.log10_exposure_lo, span = look.log10_exposure_hi - look.log10_exposure_lo;
    if (settings.curve_size < 2 || settings.curve_size > 65536)
        throw OcioError("LUT curve size " + std::to_string(settings.curve_size) + " is outside 2..65536");
    if (!(std::isfinite(lo) && std::isfinite(span) && span > 0))
        throw OcioError("the look's curves span no exposures (log10 " + format_number(lo) + " .. " +
                        format_number(look.log10_exposure_hi) + ")");
    const int n_curve = settings.curve_size, n = sized.cube_size;
    std::string summary = "Darkroom: the look's stages: an exposure matrix, log10 exposure " + format_number(lo) +
                          " .. " + format_number(look.log10_exposure_hi) + ", 1D curves of " +
                          std::to_string(n_curve) + " entries";
    if (look.table) {
        const std::string size = std::to_string(n);
        summary += ", then a 3D LUT " + size + "x" + size + "x" + size + " (tetrahedral) on the curves' values";
        if (look.table_cube_root) summary += ", holding cube roots, cubed after";
    }
    summary += prefix_summary(settings);
    if (output) summary += "; after it, the exact output conversion (" + std::to_string(output->getNumTransforms()) +
                           " OCIO operations)";
    OCIO::GroupTransformRcPtr group = clf_group(settings, summary);

    OCIO::MatrixTransformRcPtr exposure = named(OCIO::MatrixTransform::Create(), look.exposure_name);
    double m44[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) m44[4 * r + c] = look.exposure_matrix[(std::size_t)r][(std::size_t)c];
    exposure->setMatrix(m44);
    group->appendTransform(exposure);

    // (log10 x - lo) / span: the curves' domain onto the Lut1D's 0 .. 1.
    OCIO::LogAffineTransformRcPtr log = named(OCIO::LogAffineTransform::Create(), "log10 " + look.exposure_name);
    log->setBase(10.0);
    log->setLogSideSlopeValue({1.0 / span, 1.0 / span, 1.0 / span});
    log->setLogSideOffsetValue({-lo / span, -lo / span, -lo / span});
    group->appendTransform(log);

    std::vector<float> curve_inputs, curve_values;
    for (int i = 0; i < n_curve; ++i) {
        const double e = lo + span * i / double(n_curve - 1);
        double v[3];
        look.curves(e, v);
        curve_inputs.insert(curve_inputs.end(), 3, (float)e);
        curve_values.insert(curve_values.end(), {(float)v[0], (float)v[1], (float)v[2]});
    }
    check_finite(curve_values, curve_inputs);
    OCIO::Lut1DTransformRcPtr curves =
        named(OCIO::Lut1DTransform::Create((unsigned long)n_curve, false), look.curves_name);
    curves->setInterpolation(OCIO::INTERP_LINEAR);
    curves->setFileOutputBitDepth(OCIO::BIT_DEPTH_F32);
    for (int i = 0; i < n_curve; ++i)
        curves->setValue((unsigned long)i, curve_values[3 * (std::size_t)i], curve_values[3 * (std::size_t)i + 1],
                         curve_values[3 * (std::size_t)i + 2]);
    group->appendTransform(curves);

    if (look.table) {
        // The box onto the Lut3D's 0 .. 1 per axis.
        OCIO::MatrixTransformRcPtr to_box = named(OCIO::MatrixTransform::Create(), look.table_name + " domain");
        double scale[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}, offset[4] = {0, 0, 0, 0};
        std::array<std::vector<double>, 3> axes;
        for (int a = 0; a < 3; ++a) {
            const double a_lo = look.table_lo[(std::size_t)a], a_span = look.table_hi[(std::size_t)a] - a_lo;
            if (!(std::isfinite(a_lo) && std::isfinite(a_span) && a_span > 0))
                throw OcioError("the look's 3D stage spans nothing along axis " + std::to_string(a));
            scale[5 * a] = 1.0 / a_span;
            offset[a] = -a_lo / a_span;
            for (int i = 0; i < n; ++i) axes[(std::size_t)a].push_back(a_lo + a_span * i / double(n - 1));
        }
        to_box->setMatrix(scale);
        to_box->setOffset(offset);
        group->appendTransform(to_box);

        const std::vector<float> inputs = lattice_inputs(n, axes);
        std::vector<float> lattice(inputs.size());
        for (std::size_t p = 0; p < inputs.size(); p += 3) {
            const double in[3] = {inputs[p], inputs[p + 1], inputs[p + 2]};
            double out[3];
            look.table(in, out);
            for (std::size_t c = 0; c < 3; ++c)
                lattice[p + c] = (float)(look.table_cube_root ? std::cbrt(out[c]) : out[c]);
        }
        check_finite(lattice, inputs);
        group->appendTransform(named(lut3d_of(n, lattice), look.table_name));
        if (look.table_cube_root) {
            // Mirrored, so that a value below 0 (a colour outside the gamut) keeps its sign.
            OCIO::ExponentTransformRcPtr cube = named(OCIO::ExponentTransform::Create(), look.table_name + " cubed");
            cube->setValue({3.0, 3.0, 3.0, 1.0});
            cube->setNegativeStyle(OCIO::NEGATIVE_MIRROR);
            group->appendTransform(cube);
        }
    }
    append_operations(*group, output);

    BakedLut baked;
    baked.format = LutFormat::clf;
    baked.summary = summary;
    baked.text = clf_written(*group);
    return baked;
}

// The layered look's .clf, or none where the input or output conversion has no exact CLF form.
std::optional<BakedLut> layered_clf(const ColorConverter& converter, const std::string& input_space,
                                    const LayeredLook& look, LutBakeSettings settings) {
    if (!input_space.empty()) {
        const ConversionPtr to_working = converter.to_working(input_space);
        if (!to_working->is_noop()) {
            settings.clf_prefix = clf_writable_operations(*to_working->processor());
            if (!settings.clf_prefix) return std::nullopt;
        }
    }
    OCIO::ConstGroupTransformRcPtr output;
    if (look.output) {
        output = clf_writable_operations(*look.output);
        if (!output) return std::nullopt;
    }
    return bake_layered(look, settings, output);
}

}  // namespace

BakedLut bake_look(const ColorConverter& converter, const std::string& input_space,
                   const PixelFunction& look_from_working, LutBakeSettings settings, LutFormat format,
                   const LayeredLook* layered) {
    settings.clf_prefix = nullptr;
    settings.input = LutInput::scene_linear;
    if (layered && format == LutFormat::clf)
        if (std::optional<BakedLut> baked = layered_clf(converter, input_space, *layered, settings)) return *baked;
    if (input_space.empty()) return bake_lut(look_from_working, settings, format);
    const ConversionPtr to_working = converter.to_working(input_space);
    if (to_working->is_noop()) return bake_lut(look_from_working, settings, format);
    if (format == LutFormat::clf) {
        settings.clf_prefix = clf_writable_operations(*to_working->processor());
        if (settings.clf_prefix) return bake_lut(look_from_working, settings, format);
    }
    // Sample the conversion too: on the encoded values for log and video spaces.
    const std::string encoding = converter.encoding(input_space);
    if (encoding == "log" || encoding == "sdr-video" || encoding == "hdr-video") settings.input = LutInput::encoded;
    const PixelFunction folded = [&](float* rgb, std::size_t n) {
        to_working->apply_rgb(rgb, n);
        look_from_working(rgb, n);
    };
    return bake_lut(folded, settings, format);
}

}  // namespace darkroom::ocio
