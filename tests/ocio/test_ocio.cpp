// The OCIO layer: the embedded config, config precedence and errors, conversions, and
// LUTs baked here and applied by OCIO in-process and by the real oiiotool.
#include <catch2/catch.hpp>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

#include "ocio/config.h"
#include "ocio/lut_bake.h"
#include "ocio/transform.h"
#include "ocio_variable.h"

namespace fs = std::filesystem;
using namespace darkroom::ocio;

namespace {

// A fresh directory under the system temp folder, removed at the end of the test.
struct TempDir {
    fs::path path;
    TempDir() {
        static std::atomic<int> counter{0};
        path = fs::temp_directory_path() /
               ("darkroom-ocio-test-" + std::to_string(getpid()) + "-" + std::to_string(counter++));
        fs::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
    std::string file(const std::string& name) const { return (path / name).string(); }
};

void write_text(const std::string& path, const std::string& text) {
    std::ofstream out(path);
    out << text;
}

// The embedded config under another name, written as a file.
std::string write_config_copy(const TempDir& dir, const std::string& file, const std::string& name) {
    OCIO::ConfigRcPtr copy = embedded_config()->createEditableCopy();
    copy->setName(name.c_str());
    std::ostringstream yaml;
    copy->serialize(yaml);
    write_text(dir.file(file), yaml.str());
    return dir.file(file);
}

std::array<float, 3> convert(const Conversion& c, std::array<float, 3> rgb) {
    c.apply_rgb(rgb.data(), 1);
    return rgb;
}

// sRGB encoding (IEC 61966-2-1), the closed form.
double srgb_encode(double linear) {
    return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

// ---- Published colorimetry, for the ACEScg check ----
using Mat3 = std::array<std::array<double, 3>, 3>;

Mat3 mul(const Mat3& a, const Mat3& b) {
    Mat3 m{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) m[i][j] += a[i][k] * b[k][j];
    return m;
}

Mat3 inverse(const Mat3& m) {
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                       m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    Mat3 r;
    r[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) / det;
    r[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det;
    r[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det;
    r[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) / det;
    r[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det;
    r[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det;
    r[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) / det;
    r[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det;
    r[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det;
    return r;
}

std::array<double, 3> xyz_of(double x, double y) { return {x / y, 1.0, (1.0 - x - y) / y}; }

// RGB -> XYZ from chromaticities of R, G, B and white (SMPTE RP 177).
Mat3 rgb_to_xyz(const std::array<std::array<double, 2>, 3>& primaries, std::array<double, 2> white) {
    Mat3 p;
    for (int c = 0; c < 3; ++c) {
        const auto v = xyz_of(primaries[c][0], primaries[c][1]);
        for (int r = 0; r < 3; ++r) p[r][c] = v[r];
    }
    const auto w = xyz_of(white[0], white[1]);
    const Mat3 pi = inverse(p);
    std::array<double, 3> s{};
    for (int r = 0; r < 3; ++r) s[r] = pi[r][0] * w[0] + pi[r][1] * w[1] + pi[r][2] * w[2];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) p[r][c] *= s[c];
    return p;
}

// Bradford chromatic adaptation (Lam 1985; the cone matrix as in Lindbloom's tables).
Mat3 bradford(std::array<double, 2> from, std::array<double, 2> to) {
    const Mat3 m = {{{0.8951, 0.2664, -0.1614}, {-0.7502, 1.7135, 0.0367}, {0.0389, -0.0685, 1.0296}}};
    const auto a = xyz_of(from[0], from[1]), b = xyz_of(to[0], to[1]);
    std::array<double, 3> ca{}, cb{};
    for (int r = 0; r < 3; ++r) {
        ca[r] = m[r][0] * a[0] + m[r][1] * a[1] + m[r][2] * a[2];
        cb[r] = m[r][0] * b[0] + m[r][1] * b[1] + m[r][2] * b[2];
    }
    Mat3 d{};
    for (int i = 0; i < 3; ++i) d[i][i] = cb[i] / ca[i];
    return mul(inverse(m), mul(d, m));
}

// ---- The analytic look for the LUT tests ----
// A print-like look, smooth everywhere as a film look is: per channel a filmic tone
// curve in reflectance, R = R_min + (1 - R_min) / (1 + (x / x_m)^-1.5) (contrast 1.5,
// paper black R_min = 10^-2.1, scene grey 0.18 -> about 0.18); an interimage effect that
// raises saturation in density, D' = D + 0.2 (D - mean D) (channel crosstalk, which a 3D
// LUT must carry); then the sRGB display encoding: scene-linear Rec.709 -> display.
// Smooth (C1) everywhere, including at x = 0.
void filmic_look(float* rgb, std::size_t n) {
    const double contrast = 1.5, r_min = std::pow(10.0, -2.1);
    const double x_m = 0.18 / std::pow(1.0 / 0.18 - 1.0, -1.0 / contrast);
    for (std::size_t p = 0; p < n; ++p) {
        double density[3];
        for (int c = 0; c < 3; ++c) {
            const double x = std::max<double>(rgb[3 * p + c], 0.0);
            const double r = x > 0 ? r_min + (1.0 - r_min) / (1.0 + std::pow(x / x_m, -contrast)) : r_min;
            density[c] = -std::log10(r);
        }
        const double mean = (density[0] + density[1] + density[2]) / 3.0;
        for (int c = 0; c < 3; ++c) {
            // Not clipped at 1 (saturated highlights go a little above): a clip is a kink,
            // which a LUT interpolates with an error of about its slope times a cell.
            const double r = std::pow(10.0, -(density[c] + 0.2 * (density[c] - mean)));
            rgb[3 * p + c] = (float)srgb_encode(r);
        }
    }
}

// Test inputs spanning the shaper's range: greys at every third of a stop, random colours
// log-uniform over -9 .. +8 stops, some channels at exactly 0.
std::vector<float> lut_test_inputs(const LogShaper& shaper, int width, int height) {
    std::vector<float> rgb((std::size_t)width * height * 3);
    uint64_t state = 0x9E3779B97F4A7C15ull;
    auto uniform = [&state]() {  // splitmix64: deterministic on every platform
        uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return double((z ^ (z >> 31)) >> 11) / double(1ull << 53);
    };
    const std::size_t n = rgb.size() / 3;
    for (std::size_t p = 0; p < n; ++p) {
        if (p < 60) {
            const double grey = shaper.mid_grey * std::exp2(-9.0 + p / 3.0);
            rgb[3 * p] = rgb[3 * p + 1] = rgb[3 * p + 2] = (float)std::min(grey, shaper.lin_max());
            continue;
        }
        for (int c = 0; c < 3; ++c) {
            const double u = uniform();
            rgb[3 * p + c] = u < 0.03 ? 0.0f : (float)(shaper.mid_grey * std::exp2(-9.0 + 17.0 * uniform()));
        }
    }
    return rgb;
}

struct ErrorStats {
    double max = 0, mean = 0;
};

ErrorStats compare(const std::vector<float>& a, const std::vector<float>& b) {
    ErrorStats s;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const double e = std::abs((double)a[i] - (double)b[i]);
        s.max = std::max(s.max, e);
        s.mean += e;
    }
    s.mean /= double(a.size());
    return s;
}

std::vector<float> apply_lut_in_process(const std::string& lut, std::vector<float> rgb,
                                        OCIO::Interpolation interp = OCIO::INTERP_BEST) {
    OCIO::ClearAllCaches();  // OCIO caches files by path: read this one afresh
    OCIO::FileTransformRcPtr file = OCIO::FileTransform::Create();
    file->setSrc(lut.c_str());
    file->setInterpolation(interp);
    OCIO::ConstCPUProcessorRcPtr cpu = OCIO::Config::CreateRaw()->getProcessor(file)->getDefaultCPUProcessor();
    OCIO::PackedImageDesc desc(rgb.data(), (long)(rgb.size() / 3), 1, 3);
    cpu->apply(desc);
    return rgb;
}

bool oiiotool_available() { return std::system("oiiotool --help > /dev/null 2>&1") == 0; }

// The LUT's text written to `path` (the program writes it atomically; tests only need the file).
BakedLut written_to(const std::string& path, const BakedLut& baked) {
    std::ofstream(path, std::ios::binary) << baked.text;
    return baked;
}

void write_exr(const std::string& path, const std::vector<float>& rgb, int width, int height) {
    auto out = OIIO::ImageOutput::create(path);
    REQUIRE(out);
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::FLOAT);
    REQUIRE(out->open(path, spec));
    REQUIRE(out->write_image(OIIO::TypeDesc::FLOAT, rgb.data()));
    out->close();
}

std::vector<float> read_exr(const std::string& path, int width, int height) {
    auto in = OIIO::ImageInput::open(path);
    REQUIRE(in);
    REQUIRE(in->spec().width == width);
    REQUIRE(in->spec().height == height);
    std::vector<float> rgb((std::size_t)width * height * 3);
    REQUIRE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, rgb.data()));
    return rgb;
}

// Runs the real oiiotool: in.exr --ociofiletransform LUT -o out.exr (with $OCIO unset).
std::vector<float> apply_lut_with_oiiotool(const TempDir& dir, const std::string& lut, const std::vector<float>& rgb,
                                           int width, int height) {
    // oiiotool 2.4 with OCIO 2.1 needs some config even for a file transform: give it the
    // embedded one, written out.
    ScopedOcioVariable no_config(std::nullopt);
    const std::string config = dir.file("darkroom.ocio");
    write_text(config, embedded_config_yaml());
    const std::string in = dir.file("lut-in.exr"), out = dir.file("lut-out.exr");
    write_exr(in, rgb, width, height);
    const std::string command = "oiiotool --colorconfig '" + config + "' '" + in + "' --ociofiletransform '" + lut +
                                "' -d float -o '" + out + "'";
    INFO(command);
    REQUIRE(std::system(command.c_str()) == 0);
    return read_exr(out, width, height);
}

}  // namespace

// ==== The embedded config ====

TEST_CASE("embedded config is valid, complete and needs no files", "[ocio][config]") {
    OCIO::ConstConfigRcPtr config = embedded_config();
    REQUIRE(config);
    REQUIRE_NOTHROW(config->validate());
    const std::string yaml = embedded_config_yaml();
    CHECK(yaml.find("FileTransform") == std::string::npos);
    CHECK(config->getMajorVersion() == 2);
    CHECK(config->getMinorVersion() == 1);

    for (const char* name : {"ACES2065-1", "ACEScg", "ACEScct", "ACEScc", "lin_rec709", "sRGB - Texture",
                             "ARRI LogC3 (EI800) - AWG", "Sony S-Log3 - S-Gamut3", "RED Log3G10 - REDWideGamutRGB",
                             "Canon Log 3 - Cinema Gamut", "Panasonic V-Log - V-Gamut", "ADX10", "Cineon Log", "Raw",
                             "sRGB - Display", "Rec.1886 Rec.709 - Display"})
        CHECK(config->getColorSpace(name) != nullptr);
    // Aliases and roles a user would try.
    for (const char* alias : {"Linear Rec.709 (sRGB)", "lin_srgb", "scene_linear", "srgb", "logc3", "cineon", "KodakLog"})
        CHECK(config->getColorSpace(alias) != nullptr);
    CHECK(std::string(config->getColorSpace("scene_linear")->getName()) == "lin_rec709");
    CHECK(std::string(config->getDefaultDisplay()) == "sRGB");
    CHECK(std::string(config->getDefaultView("sRGB")) == "Standard");
    const std::vector<std::string> views = {"Standard", "ACES 1.0 - SDR Video", "Raw"};
    CHECK(view_names(*config, "Rec.1886 Rec.709") == views);

    // Every colour space converts to the working space (every built-in resolves).
    ColorConverter converter(embedded_active_config());
    for (const std::string& name : color_space_names(*config))
        if (config->getColorSpace(name.c_str())->getReferenceSpaceType() == OCIO::REFERENCE_SPACE_SCENE)
            CHECK_NOTHROW(converter.to_working(name));
}

TEST_CASE("0.18 linear Rec.709 goes to the sRGB display as the sRGB encoding of 0.18", "[ocio][convert]") {
    ColorConverter converter(embedded_active_config());
    const double expected = srgb_encode(0.18);  // 1.055 * 0.18^(1/2.4) - 0.055 = 0.461356
    CHECK(expected == Approx(0.461356).margin(1e-6));

    for (const ConversionPtr& c : {converter.to_display("sRGB", "Standard"), converter.to_display("", ""),
                                   converter.to_display("srgb", "standard"),
                                   converter.from_working("sRGB - Texture")}) {
        const auto out = convert(*c, {0.18f, 0.18f, 0.18f});
        for (float v : out) CHECK(v == Approx(expected).margin(2e-5));
    }
    // Rec.1886: the inverse of a pure 2.4 power.
    const auto rec1886 = convert(*converter.to_display("Rec.1886 Rec.709", "Standard"), {0.18f, 0.18f, 0.18f});
    CHECK(rec1886[1] == Approx(std::pow(0.18, 1.0 / 2.4)).margin(2e-5));
    // Back in: sRGB-encoded grey decodes to 0.18.
    const auto back = convert(*converter.to_working("sRGB"), {(float)expected, (float)expected, (float)expected});
    CHECK(back[0] == Approx(0.18).margin(1e-5));
    // Cineon: reference white (code 685) is 1.0, reference black (code 95) is 0.
    const auto cineon = convert(*converter.to_working("cineon"), {685.0f / 1023, 95.0f / 1023, 0.5f});
    CHECK(cineon[0] == Approx(1.0).margin(1e-5));
    CHECK(cineon[1] == Approx(0.0).margin(1e-5));

    // The embedded config written out is a config oiiotool uses the same way.
    if (oiiotool_available()) {
        TempDir dir;
        const std::string config = dir.file("darkroom.ocio"), in = dir.file("grey.exr"), out = dir.file("shown.exr");
        write_text(config, embedded_config_yaml());
        write_exr(in, std::vector<float>(4 * 3, 0.18f), 2, 2);
        ScopedOcioVariable unset(std::nullopt);
        const std::string command = "oiiotool --colorconfig '" + config + "' '" + in +
                                    "' --iscolorspace lin_rec709 --ociodisplay sRGB Standard -d float -o '" + out + "'";
        INFO(command);
        REQUIRE(std::system(command.c_str()) == 0);
        for (float v : read_exr(out, 2, 2)) CHECK(v == Approx(expected).margin(2e-5));
    }
}

TEST_CASE("ACEScg <-> lin_rec709 matches the matrices from the published primaries", "[ocio][convert]") {
    // ITU-R BT.709-6 primaries, D65 white (0.3127, 0.3290); ACES AP1 primaries and ACES
    // white (0.32168, 0.33767) from SMPTE ST 2065-1 / Academy TB-2014-004; Bradford CAT.
    const Mat3 rec709_to_xyz = rgb_to_xyz({{{0.640, 0.330}, {0.300, 0.600}, {0.150, 0.060}}}, {0.3127, 0.3290});
    const Mat3 ap1_to_xyz = rgb_to_xyz({{{0.713, 0.293}, {0.165, 0.830}, {0.128, 0.044}}}, {0.32168, 0.33767});
    const Mat3 rec709_to_ap1 =
        mul(inverse(ap1_to_xyz), mul(bradford({0.3127, 0.3290}, {0.32168, 0.33767}), rec709_to_xyz));
    // The matrix as widely published (e.g. "BT709_TO_AP1_MAT, with Bradford" in ACES
    // implementations), to ten digits.
    const Mat3 published = {{{0.6130974024, 0.3395231462, 0.0473794514},
                             {0.0701937225, 0.9163538791, 0.0134523985},
                             {0.0206155929, 0.1095697729, 0.8698146342}}};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) CHECK(rec709_to_ap1[r][c] == Approx(published[r][c]).margin(2e-6));

    ColorConverter converter(embedded_active_config());
    const ConversionPtr to_acescg = converter.from_working("ACEScg");
    const ConversionPtr from_acescg = converter.to_working("ACEScg");
    const Mat3 ap1_to_rec709 = inverse(rec709_to_ap1);
    const std::vector<std::array<float, 3>> samples = {
        {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.18f, 0.18f, 0.18f}, {0.9f, 0.35f, 0.05f}, {4.0f, 0.02f, 1.5f}};
    for (const auto& s : samples) {
        const auto ap1 = convert(*to_acescg, s);
        const auto back = convert(*from_acescg, s);
        for (int r = 0; r < 3; ++r) {
            const auto& m = rec709_to_ap1[r];
            const auto& n = ap1_to_rec709[r];
            const double want_ap1 = m[0] * s[0] + m[1] * s[1] + m[2] * s[2];
            const double want_709 = n[0] * s[0] + n[1] * s[1] + n[2] * s[2];
            CHECK(ap1[r] == Approx(want_ap1).margin(2e-5));
            CHECK(back[r] == Approx(want_709).margin(2e-5));
        }
        // And the round trip.
        const auto round = convert(*from_acescg, ap1);
        for (int r = 0; r < 3; ++r) CHECK(round[r] == Approx(s[r]).margin(2e-5));
    }
}

// ==== Config precedence and errors ====

TEST_CASE("config precedence: explicit file, then the OCIO variable, then embedded", "[ocio][config]") {
    TempDir dir;
    const std::string show = write_config_copy(dir, "show.ocio", "test-show-config");
    const std::string env = write_config_copy(dir, "env.ocio", "test-env-config");

    auto srgb_of_grey = [](const ActiveConfig& active) {
        return convert(*ColorConverter(active).to_display("sRGB", "Standard"), {0.18f, 0.18f, 0.18f})[0];
    };

    SECTION("nothing given: the embedded config") {
        ScopedOcioVariable unset(std::nullopt);
        const ActiveConfig active = resolve_config();
        CHECK(active.source == ConfigSource::embedded);
        CHECK(active.describe().find("$OCIO is not set") != std::string::npos);
        CHECK(srgb_of_grey(active) == Approx(srgb_encode(0.18)).margin(2e-5));
    }
    SECTION("an empty $OCIO counts as unset") {
        ScopedOcioVariable empty(std::string(""));
        CHECK(resolve_config().source == ConfigSource::embedded);
    }
    SECTION("given by flag") {
        ScopedOcioVariable unset(std::nullopt);
        const ActiveConfig active = resolve_config(show);
        CHECK(active.source == ConfigSource::explicit_file);
        CHECK(std::string(active.config->getName()) == "test-show-config");
        CHECK(active.describe().find(show) != std::string::npos);
        CHECK(active.describe().find("--colorconfig") != std::string::npos);
        CHECK(srgb_of_grey(active) == Approx(srgb_encode(0.18)).margin(2e-5));
    }
    SECTION("given by $OCIO") {
        ScopedOcioVariable set(env);
        const ActiveConfig active = resolve_config();
        CHECK(active.source == ConfigSource::environment);
        CHECK(std::string(active.config->getName()) == "test-env-config");
        CHECK(active.describe().find("$OCIO") != std::string::npos);
        CHECK(srgb_of_grey(active) == Approx(srgb_encode(0.18)).margin(2e-5));
    }
    SECTION("the flag wins over $OCIO") {
        ScopedOcioVariable set(env);
        const ActiveConfig active = resolve_config(show, "the OFX host");
        CHECK(active.source == ConfigSource::explicit_file);
        CHECK(std::string(active.config->getName()) == "test-show-config");
        CHECK(active.describe().find("the OFX host") != std::string::npos);
    }
    SECTION("a host's config object") {
        const ActiveConfig active = from_host_config(OCIO::Config::CreateFromFile(show.c_str()), "the OFX host");
        CHECK(active.source == ConfigSource::host_config);
        CHECK(srgb_of_grey(active) == Approx(srgb_encode(0.18)).margin(2e-5));
    }
}

TEST_CASE("a missing or invalid config is an error naming the file, never the embedded one", "[ocio][config]") {
    TempDir dir;
    const std::string missing = dir.file("no-such-config.ocio");
    const std::string garbage = dir.file("garbage.ocio");
    write_text(garbage, "this: [is not: an OCIO config\n");
    // Valid YAML, but a role names a colour space the config lacks.
    std::string yaml = embedded_config_yaml();
    const std::string role_line = "color_timing: ACEScct";
    REQUIRE(yaml.find(role_line) != std::string::npos);
    yaml.replace(yaml.find(role_line), role_line.size(), "color_timing: NoSuchSpace");
    const std::string bad_role = dir.file("bad-role.ocio");
    write_text(bad_role, yaml);

    auto message_of = [](auto&& f) -> std::string {
        try {
            f();
        } catch (const ConfigError& e) {
            return e.what();
        }
        return "(no ConfigError)";
    };
    ScopedOcioVariable unset(std::nullopt);
    SECTION("missing, by flag") {
        const std::string m = message_of([&] { resolve_config(missing); });
        CHECK(m.find(missing) != std::string::npos);
        CHECK(m.find("does not exist") != std::string::npos);
        CHECK(m.find("--colorconfig") != std::string::npos);
    }
    SECTION("missing, by $OCIO: an error too, saying it came from $OCIO") {
        ScopedOcioVariable set(missing);
        const std::string m = message_of([&] { resolve_config(); });
        CHECK(m.find(missing) != std::string::npos);
        CHECK(m.find("$OCIO") != std::string::npos);
    }
    SECTION("not a config") {
        const std::string m = message_of([&] { resolve_config(garbage); });
        CHECK(m.find(garbage) != std::string::npos);
        CHECK(m.find("cannot be read") != std::string::npos);
    }
    SECTION("a directory") {
        const std::string m = message_of([&] { resolve_config(dir.path.string()); });
        CHECK(m.find("directory") != std::string::npos);
    }
    SECTION("invalid contents") {
        const std::string m = message_of([&] { resolve_config(bad_role); });
        CHECK(m.find(bad_role) != std::string::npos);
        CHECK(m.find("NoSuchSpace") != std::string::npos);
    }
}

TEST_CASE("a built-in config name this OCIO cannot load gives the embedded config, with a warning",
          "[ocio][config]") {
    if (OCIO::GetVersionHex() >= 0x02020000) {
        WARN("OCIO " << OCIO::GetVersion() << " loads its built-in configs: skipped");
        return;
    }
    SECTION("by $OCIO, as hosts set it") {
        ScopedOcioVariable set(std::string("ocio://default"));
        const ActiveConfig active = resolve_config();
        CHECK(active.source == ConfigSource::embedded);
        CHECK(active.config == embedded_config());
        CHECK(active.warning.find("$OCIO names 'ocio://default'") != std::string::npos);
        CHECK(active.describe().find("ocio://default") != std::string::npos);
    }
    SECTION("given explicitly") {
        ScopedOcioVariable unset(std::nullopt);
        const ActiveConfig active = resolve_config("ocio://cg-config-latest", "the OFX host");
        CHECK(active.source == ConfigSource::embedded);
        CHECK(active.warning.find("the OFX host names 'ocio://cg-config-latest'") != std::string::npos);
    }
    SECTION("a file is never replaced, whatever its name holds") {
        ScopedOcioVariable unset(std::nullopt);
        CHECK(resolve_config().warning.empty());
        CHECK_THROWS_AS(resolve_config("shots/ocio://default"), ConfigError);
    }
}

TEST_CASE("a config without displays is an error naming the config", "[ocio][config]") {
    TempDir dir;
    const std::string path = dir.file("no-displays.ocio");
    write_text(path,
               "ocio_profile_version: 2.1\n"
               "roles:\n  default: lin_rec709\n  scene_linear: lin_rec709\n"
               "file_rules:\n  - !<Rule> {name: Default, colorspace: default}\n"
               "displays: {}\n"
               "colorspaces:\n"
               "  - !<ColorSpace>\n    name: lin_rec709\n    encoding: scene-linear\n");
    ScopedOcioVariable unset(std::nullopt);
    // OCIO 2.1 holds a config without displays invalid, so it fails as it loads.
    try {
        resolve_config(path);
        FAIL("expected a ConfigError");
    } catch (const ConfigError& e) {
        const std::string m = e.what();
        CHECK(m.find(path) != std::string::npos);
        CHECK(m.find("no default display") != std::string::npos);
    }
}

TEST_CASE("unknown names are errors that list the known ones", "[ocio][convert]") {
    ColorConverter converter(embedded_active_config());
    try {
        converter.to_working("NoSuchSpace");
        FAIL("expected UnknownNameError");
    } catch (const UnknownNameError& e) {
        const std::string m = e.what();
        CHECK(m.find("'NoSuchSpace'") != std::string::npos);
        CHECK(m.find("embedded") != std::string::npos);
        CHECK(m.find("'ACEScg'") != std::string::npos);
        CHECK(m.find("'lin_rec709'") != std::string::npos);
    }
    try {
        converter.to_display("Cinema", "Standard");
        FAIL("expected UnknownNameError");
    } catch (const UnknownNameError& e) {
        CHECK(std::string(e.what()).find("'Rec.1886 Rec.709'") != std::string::npos);
    }
    try {
        converter.to_display("sRGB", "Filmic");
        FAIL("expected UnknownNameError");
    } catch (const UnknownNameError& e) {
        CHECK(std::string(e.what()).find("'ACES 1.0 - SDR Video'") != std::string::npos);
    }
    CHECK_THROWS_AS(converter.from_working(""), UnknownNameError);
}

// ==== Conversions ====

TEST_CASE("no-op conversions are detected and skipped, and conversions are cached", "[ocio][convert]") {
    ColorConverter converter(embedded_active_config());
    for (const char* same : {"lin_rec709", "scene_linear", "Linear Rec.709 (sRGB)", "linear", "Raw", "data"})
        CHECK(converter.to_working(same)->is_noop());
    CHECK(converter.from_working("lin_srgb")->is_noop());
    CHECK_FALSE(converter.to_working("ACEScg")->is_noop());
    CHECK_FALSE(converter.to_display("sRGB", "Standard")->is_noop());
    // The Raw view passes data through.
    CHECK(converter.to_display("sRGB", "Raw")->is_noop());

    // A no-op leaves every bit alone, NaN included.
    std::vector<float> pixels = {0.5f, std::nanf(""), -3.0f, 1e30f};
    const std::vector<float> before = pixels;
    converter.to_working("scene_linear")->apply(PixelBuffer::packed(pixels.data(), 1, 1, 4));
    CHECK(std::memcmp(pixels.data(), before.data(), sizeof(float) * 4) == 0);

    // Asked twice (also through another converter on the same config): the same object.
    CHECK(converter.to_working("ACEScg") == converter.to_working("ACEScg"));
    CHECK(ColorConverter(embedded_active_config()).to_working("ACEScg") == converter.to_working("ACEScg"));
}

TEST_CASE("buffers: strides, alpha, grey and bottom-up rows", "[ocio][convert]") {
    ColorConverter converter(embedded_active_config());
    const ConversionPtr to_srgb = converter.from_working("sRGB - Texture");
    const float e = (float)srgb_encode(0.18);

    // RGBA: alpha untouched.
    std::vector<float> rgba = {0.18f, 0.18f, 0.18f, 0.25f, 0.18f, 0.18f, 0.18f, 0.75f};
    to_srgb->apply(PixelBuffer::packed(rgba.data(), 2, 1, 4));
    CHECK(rgba[0] == Approx(e).margin(2e-5));
    CHECK(rgba[3] == 0.25f);
    CHECK(rgba[6] == Approx(e).margin(2e-5));
    CHECK(rgba[7] == 0.75f);

    // One channel: treated as grey.
    std::vector<float> grey = {0.18f, 0.18f};
    to_srgb->apply(PixelBuffer::packed(grey.data(), 2, 1, 1));
    CHECK(grey[1] == Approx(e).margin(2e-5));

    // A 2x2 RGB image addressed bottom-up (negative row stride), inside a wider buffer.
    std::vector<float> wide(2 * 3 * 3, -1.0f);  // rows of 3 pixels, only 2 used
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 2; ++x)
            for (int c = 0; c < 3; ++c) wide[(std::size_t)(y * 9 + x * 3 + c)] = 0.18f;
    PixelBuffer view{wide.data() + 9, 2, 2, 3, 3, -9};
    to_srgb->apply(view);
    CHECK(wide[0] == Approx(e).margin(2e-5));
    CHECK(wide[9 + 3 + 2] == Approx(e).margin(2e-5));
    CHECK(wide[6] == -1.0f);   // the unused third pixel of each row
    CHECK(wide[15] == -1.0f);
}

TEST_CASE("a user config without lin_rec709 reaches it through aces_interchange", "[ocio][convert]") {
    OCIO::ConfigRcPtr copy = embedded_config()->createEditableCopy();
    for (const char* role : {OCIO::ROLE_SCENE_LINEAR, OCIO::ROLE_DEFAULT, OCIO::ROLE_RENDERING})
        copy->setRole(role, "ACEScg");
    copy->removeColorSpace("lin_rec709");
    REQUIRE_NOTHROW(copy->validate());
    ColorConverter via_aces(from_host_config(copy, "the test"));
    CHECK(via_aces.working_space().color_space.empty());
    CHECK(via_aces.working_space().aces_interchange == "ACES2065-1");
    CHECK(via_aces.working_space().describe().find("aces_interchange") != std::string::npos);

    ColorConverter embedded(embedded_active_config());
    for (const char* cs : {"ACEScg", "sRGB - Texture", "Sony S-Log3 - S-Gamut3"}) {
        const auto a = convert(*via_aces.to_working(cs), {0.3f, 0.5f, 0.7f});
        const auto b = convert(*embedded.to_working(cs), {0.3f, 0.5f, 0.7f});
        for (int c = 0; c < 3; ++c) CHECK(a[c] == Approx(b[c]).margin(1e-5));
    }
    const auto grey = convert(*via_aces.to_display("sRGB", "Standard"), {0.18f, 0.18f, 0.18f});
    CHECK(grey[0] == Approx(srgb_encode(0.18)).margin(2e-5));

    // Neither a known name nor the role: conversions say so, naming the config.
    copy->setRole(OCIO::ROLE_INTERCHANGE_SCENE, nullptr);
    copy->setRole(OCIO::ROLE_REFERENCE, nullptr);
    ColorConverter lost(from_host_config(copy, "the test"));
    CHECK_THROWS_WITH(lost.to_working("ACEScg"), Catch::Contains("aces_interchange") && Catch::Contains("the test"));
}

TEST_CASE("conversions from several threads at once agree", "[ocio][convert]") {
    ColorConverter converter(embedded_active_config());
    const int n_threads = 8, n_pixels = 4096;
    std::vector<float> reference((std::size_t)n_pixels * 3);
    for (int i = 0; i < n_pixels * 3; ++i) reference[(std::size_t)i] = 0.001f * (float)(i % 997);
    std::vector<float> expected = reference;
    converter.to_display("sRGB", "ACES 1.0 - SDR Video")->apply_rgb(expected.data(), (std::size_t)n_pixels);

    std::vector<std::vector<float>> results((std::size_t)n_threads, reference);
    std::vector<std::thread> threads;
    for (int t = 0; t < n_threads; ++t)
        threads.emplace_back([&, t] {
            // Each thread asks for the conversion itself: the cache is shared.
            converter.to_display("sRGB", "ACES 1.0 - SDR Video")->apply_rgb(results[(std::size_t)t].data(), n_pixels);
        });
    for (std::thread& th : threads) th.join();
    for (const auto& r : results) CHECK(std::memcmp(r.data(), expected.data(), sizeof(float) * expected.size()) == 0);

    // One buffer on several row bands: the same bits as one thread.
    std::vector<float> banded = reference;
    converter.to_display("sRGB", "ACES 1.0 - SDR Video")->apply(PixelBuffer::packed(banded.data(), 64, 64, 3), 3);
    CHECK(std::memcmp(banded.data(), expected.data(), sizeof(float) * expected.size()) == 0);
}

// ==== LUT baking ====

TEST_CASE("the log2 shaper", "[ocio][lut]") {
    const LogShaper shaper;  // grey 0.18, -8 .. +8 stops
    CHECK(shaper.toe_break() == Approx(0.18 / 256));
    CHECK(shaper.lin_max() == Approx(0.18 * 256));
    CHECK(shaper.to_shaper(0.0) == 0.0);
    CHECK(shaper.to_shaper(shaper.lin_max()) == Approx(1.0));
    // Evenly spaced in stops above the toe.
    const double stop = shaper.to_shaper(0.36) - shaper.to_shaper(0.18);
    CHECK(stop == Approx(shaper.slope()));
    CHECK(shaper.to_shaper(0.18 * 16) - shaper.to_shaper(0.18 * 8) == Approx(stop));
    // Continuous at the break, and inverse.
    const double b = shaper.toe_break();
    CHECK(shaper.to_shaper(b * (1 - 1e-9)) == Approx(shaper.to_shaper(b)).epsilon(1e-8));
    for (double x : {0.0, 1e-5, 0.0007, 0.01, 0.18, 1.0, 40.0})
        CHECK(shaper.from_shaper(shaper.to_shaper(x)) == Approx(x).epsilon(1e-12).margin(1e-15));
}

TEST_CASE("a baked LUT of an analytic look matches it, in OCIO and in oiiotool", "[ocio][lut]") {
    TempDir dir;
    const LutBakeSettings settings;  // defaults: 65^3, log2 shaper -8 .. +8 stops
    const int width = 64, height = 64;
    const std::vector<float> inputs = lut_test_inputs(settings.shaper, width, height);
    std::vector<float> expected = inputs;
    filmic_look(expected.data(), expected.size() / 3);
    const bool have_oiiotool = oiiotool_available();
    if (!have_oiiotool) WARN("oiiotool is not installed: the oiiotool half of this test is skipped");

    for (const char* name : {"look.clf", "look.cube"}) {
        const std::string lut = dir.file(name);
        const BakedLut baked = written_to(lut, bake_lut(filmic_look, settings, lut_format_for_path(lut)));
        CHECK(baked.summary.find("65x65x65") != std::string::npos);
        REQUIRE(fs::exists(lut));

        const ErrorStats ocio = compare(apply_lut_in_process(lut, inputs), expected);
        std::printf("[lut accuracy] %-9s 65^3, OCIO in-process: max %.5f, mean %.6f (display, full scale 1)\n", name,
                    ocio.max, ocio.mean);
        CHECK(ocio.max < 0.005);
        if (have_oiiotool) {
            const ErrorStats tool = compare(apply_lut_with_oiiotool(dir, lut, inputs, width, height), expected);
            std::printf("[lut accuracy] %-9s 65^3, oiiotool:         max %.5f, mean %.6f\n", name, tool.max, tool.mean);
            CHECK(tool.max < 0.005);
        }
    }
}

TEST_CASE("baked LUTs clamp outside the shaper range as documented", "[ocio][lut]") {
    TempDir dir;
    LutBakeSettings settings;
    settings.cube_size = 33;
    settings.title = "Darkroom test look";
    settings.description = "film: test\nprint: test";  // comments / Description elements
    const float x_hi = (float)settings.shaper.lin_max();
    std::vector<float> edge = {0, 0, 0, x_hi, x_hi, x_hi};
    filmic_look(edge.data(), 2);
    for (const char* name : {"clamp.clf", "clamp.cube"}) {
        const std::string lut = dir.file(name);
        written_to(lut, bake_lut(filmic_look, settings, lut_format_for_path(lut)));
        const std::vector<float> out = apply_lut_in_process(lut, {-0.5f, -0.5f, -0.5f, 1000.0f, 1000.0f, 1000.0f});
        INFO(name);
        for (int c = 0; c < 3; ++c) {
            CHECK(out[(std::size_t)c] == Approx(edge[(std::size_t)c]).margin(1e-5));
            CHECK(out[(std::size_t)(3 + c)] == Approx(edge[(std::size_t)(3 + c)]).margin(1e-5));
        }
    }
}

TEST_CASE("LUTs for pictures in a log space (ACEScct)", "[ocio][lut]") {
    TempDir dir;
    ColorConverter converter(embedded_active_config());
    const ConversionPtr from_log = converter.to_working("ACEScct");
    // Plate-like colours inside the Rec.709 gamut (channel ratios up to 3:1) over -7 .. +6
    // stops, encoded as ACEScct. (Far outside it, where a Rec.709 channel crosses 0, the
    // look clips negative light: a kink, which a LUT on log input resolves coarsely.)
    const int width = 64, height = 16;
    std::vector<float> inputs;
    for (int i = 0; i < width * height; ++i) {
        const double level = 0.18 * std::exp2(-7.0 + 13.0 * i / (width * height - 1.0));
        for (int c = 0; c < 3; ++c) inputs.push_back((float)(level * (1.0 + 0.5 * std::sin(0.37 * i + 2.1 * c))));
    }
    converter.from_working("ACEScct")->apply_rgb(inputs.data(), inputs.size() / 3);
    std::vector<float> expected = inputs;
    from_log->apply_rgb(expected.data(), expected.size() / 3);
    filmic_look(expected.data(), expected.size() / 3);
    const bool have_oiiotool = oiiotool_available();

    SECTION(".clf: the exact ACEScct decode, then the shaper and the LUT") {
        const std::string lut = dir.file("acescct.clf");
        const BakedLut baked =
            written_to(lut, bake_look(converter, "ACEScct", filmic_look, LutBakeSettings(), lut_format_for_path(lut)));
        CHECK(baked.summary.find("exact conversion") != std::string::npos);
        const ErrorStats e = compare(apply_lut_in_process(lut, inputs), expected);
        std::printf("[lut accuracy] ACEScct .clf  65^3, OCIO in-process: max %.5f, mean %.6f\n", e.max, e.mean);
        CHECK(e.max < 0.005);
        if (have_oiiotool) {
            const ErrorStats t = compare(apply_lut_with_oiiotool(dir, lut, inputs, width, height), expected);
            std::printf("[lut accuracy] ACEScct .clf  65^3, oiiotool:         max %.5f, mean %.6f\n", t.max, t.mean);
            CHECK(t.max < 0.005);
        }
    }
    SECTION(".cube: a plain 3D LUT on the ACEScct values") {
        const std::string lut = dir.file("acescct.cube");
        const BakedLut baked =
            written_to(lut, bake_look(converter, "ACEScct", filmic_look, LutBakeSettings(), lut_format_for_path(lut)));
        CHECK(baked.summary.find("encoded input") != std::string::npos);
        std::ifstream text(lut);
        const std::string contents((std::istreambuf_iterator<char>(text)), std::istreambuf_iterator<char>());
        CHECK(contents.find("LUT_1D_SIZE") == std::string::npos);
        const ErrorStats e = compare(apply_lut_in_process(lut, inputs), expected);
        std::printf("[lut accuracy] ACEScct .cube 65^3, OCIO in-process: max %.5f, mean %.6f\n", e.max, e.mean);
        // The AP1 -> Rec.709 matrix sampled on a log lattice: documented as about 2 %.
        CHECK(e.max < 0.02);
        if (have_oiiotool) {
            const ErrorStats t = compare(apply_lut_with_oiiotool(dir, lut, inputs, width, height), expected);
            std::printf("[lut accuracy] ACEScct .cube 65^3, oiiotool:         max %.5f, mean %.6f\n", t.max, t.mean);
            CHECK(t.max < 0.02);
        }
    }
    SECTION("pictures already in the working space: no input operations") {
        const BakedLut baked = bake_look(converter, "scene_linear", filmic_look, LutBakeSettings(), LutFormat::clf);
        CHECK(baked.summary.find("exact conversion") == std::string::npos);
        CHECK(baked.summary.find("log2 shaper") != std::string::npos);
    }
}

// A film-like look in stages: a sensitivity matrix to lux-seconds, S-shaped H&D curves
// against log10 exposure, and a print-like 3D function of the three densities (light
// falling by decades, with crosstalk), shown on the sRGB display.
LayeredLook film_like_look(const ColorConverter& converter) {
    LayeredLook look;
    look.exposure_matrix = {{{0.045, 0.004, 0.001}, {0.0025, 0.0425, 0.005}, {0.0005, 0.006, 0.0435}}};
    look.log10_exposure_lo = -5.0;
    look.log10_exposure_hi = 1.0;
    look.curves = [](double e, double* density) {
        for (int c = 0; c < 3; ++c) density[c] = 0.2 + 2.2 / (1.0 + std::exp(-2.0 * (e + 2.05 + 0.05 * (c - 1))));
    };
    look.table = [](const double* d, double* rgb) {
        for (int c = 0; c < 3; ++c)
            rgb[c] = std::pow(10.0, 0.9 * (d[c] - 0.2) + 0.15 * (d[(c + 1) % 3] - d[c]) - 2.0);
    };
    look.table_lo = {0.1, 0.1, 0.1};
    look.table_hi = {2.5, 2.5, 2.5};
    look.table_cube_root = true;
    look.output = converter.to_display("sRGB", "Standard")->processor();
    return look;
}

// The same look evaluated directly (the stages clamp as the file's do).
std::vector<float> film_like_expected(const ColorConverter& converter, const LayeredLook& look,
                                      std::vector<float> rgb) {
    for (std::size_t p = 0; p < rgb.size(); p += 3) {
        double v[3];
        for (std::size_t c = 0; c < 3; ++c) {
            double exposure = 0;
            for (std::size_t k = 0; k < 3; ++k) exposure += look.exposure_matrix[c][k] * rgb[p + k];
            const double e = exposure > 0 ? std::clamp(std::log10(exposure), look.log10_exposure_lo,
                                                       look.log10_exposure_hi)
                                          : look.log10_exposure_lo;
            double curves[3];
            look.curves(e, curves);
            v[c] = std::clamp(curves[c], look.table_lo[c], look.table_hi[c]);
        }
        double out[3];
        look.table(v, out);
        for (std::size_t c = 0; c < 3; ++c) rgb[p + c] = (float)out[c];
    }
    converter.to_display("sRGB", "Standard")->apply_rgb(rgb.data(), rgb.size() / 3);
    return rgb;
}

TEST_CASE("a layered look's .clf holds its stages and matches the look", "[ocio][lut]") {
    TempDir dir;
    ColorConverter converter(embedded_active_config());
    const LayeredLook look = film_like_look(converter);
    const int width = 64, height = 64;
    const std::vector<float> inputs = lut_test_inputs(LogShaper(), width, height);
    const std::vector<float> expected = film_like_expected(converter, look, inputs);
    const PixelFunction sampled = [&](float* rgb, std::size_t n) {
        const std::vector<float> out = film_like_expected(converter, look, std::vector<float>(rgb, rgb + 3 * n));
        std::copy(out.begin(), out.end(), rgb);
    };

    const std::string lut = dir.file("layered.clf");
    const BakedLut baked = written_to(lut, bake_look(converter, "", sampled, LutBakeSettings(), LutFormat::clf, &look));
    CHECK(baked.summary.find("1D curves of 16384 entries") != std::string::npos);
    CHECK(baked.summary.find("3D LUT 65x65x65") != std::string::npos);
    // In the model's order: matrix, log, curves, the box, the 3D LUT, its cube, the display.
    std::size_t at = 0;
    for (const char* node : {"<Matrix", "<Log", "<LUT1D", "<Matrix", "<LUT3D", "<Exponent", "<Exponent"}) {
        INFO(node);
        at = baked.text.find(node, at);
        REQUIRE(at != std::string::npos);
        ++at;
    }
    const ErrorStats ocio = compare(apply_lut_in_process(lut, inputs), expected);
    std::printf("[lut accuracy] layered .clf 65^3, OCIO in-process: max %.6f, mean %.7f\n", ocio.max, ocio.mean);
    CHECK(ocio.max < 0.001);
    if (oiiotool_available()) {
        const ErrorStats tool = compare(apply_lut_with_oiiotool(dir, lut, inputs, width, height), expected);
        std::printf("[lut accuracy] layered .clf 65^3, oiiotool:         max %.6f, mean %.7f\n", tool.max, tool.mean);
        CHECK(tool.max < 0.001);
    }

    // From ACEScct: the exact decode first, then the same stages.
    std::vector<float> acescct = inputs;
    converter.from_working("ACEScct")->apply_rgb(acescct.data(), acescct.size() / 3);
    const std::string from_log = dir.file("layered-acescct.clf");
    written_to(from_log, bake_look(converter, "ACEScct", sampled, LutBakeSettings(), LutFormat::clf, &look));
    CHECK(compare(apply_lut_in_process(from_log, acescct), expected).max < 0.001);

    // A .cube cannot hold the stages: the whole look is sampled.
    const BakedLut cube = bake_look(converter, "", sampled, LutBakeSettings(), LutFormat::cube, &look);
    CHECK(cube.summary.find("1D curves") == std::string::npos);
    CHECK(cube.summary.find("log2 shaper") != std::string::npos);
}

// (A file that cannot be written: `cli: bake-lut ...`, since the program writes it.)
TEST_CASE("LUT baking refuses bad input", "[ocio][lut]") {
    LutBakeSettings settings;
    settings.cube_size = 9;
    CHECK_THROWS_WITH(lut_format_for_path("look.3dl"), Catch::Contains(".cube or .clf"));
    settings.cube_size = 200;
    CHECK_THROWS_AS(bake_lut(filmic_look, settings, LutFormat::cube), OcioError);
    settings.cube_size = 9;
    const PixelFunction broken = [](float* rgb, std::size_t n) {
        filmic_look(rgb, n);
        rgb[3 * (n / 2)] = std::nanf("");
    };
    CHECK_THROWS_WITH(bake_lut(broken, settings, LutFormat::clf), Catch::Contains("non-finite"));
}

// Not run by default (hidden tag): the accuracy table for the documentation, with
// `test_ocio "[.lut-accuracy]"`. Display code values, full scale 1. A CLF's LUT3D carries
// its own interpolation (tetrahedral, as written), so only .cube rows show trilinear.
TEST_CASE("LUT accuracy against size", "[.lut-accuracy]") {
    TempDir dir;
    ColorConverter converter(embedded_active_config());
    const int width = 128, height = 128;
    const LogShaper default_shaper;
    const std::vector<float> linear_inputs = lut_test_inputs(default_shaper, width, height);
    // In-gamut colours over -7 .. +6 stops, as ACEScct.
    std::vector<float> acescct_inputs;
    for (int i = 0; i < width * height; ++i) {
        const double level = 0.18 * std::exp2(-7.0 + 13.0 * i / (width * height - 1.0));
        for (int c = 0; c < 3; ++c)
            acescct_inputs.push_back((float)(level * (1.0 + 0.5 * std::sin(0.37 * i + 2.1 * c))));
    }
    converter.from_working("ACEScct")->apply_rgb(acescct_inputs.data(), acescct_inputs.size() / 3);

    int serial = 0;
    for (const char* input : {"lin_rec709", "ACEScct"}) {
        const std::vector<float>& inputs = std::string(input) == "ACEScct" ? acescct_inputs : linear_inputs;
        std::vector<float> expected = inputs;
        converter.to_working(input)->apply_rgb(expected.data(), expected.size() / 3);
        filmic_look(expected.data(), expected.size() / 3);
        for (int cube : {17, 33, 48, 65}) {
            for (int shaper : {0, 4096, 16384, 65536}) {
                const bool clf = shaper == 0;
                if (!clf && std::string(input) == "ACEScct" && shaper != 16384) continue;  // no shaper there
                LutBakeSettings settings;
                settings.cube_size = cube;
                if (!clf) settings.cube_shaper_size = shaper;
                const std::string lut = dir.file("acc" + std::to_string(serial++) + (clf ? ".clf" : ".cube"));
                written_to(lut, bake_look(converter, input, filmic_look, settings, lut_format_for_path(lut)));
                const ErrorStats tet = compare(apply_lut_in_process(lut, inputs, OCIO::INTERP_TETRAHEDRAL), expected);
                const ErrorStats tri = compare(apply_lut_in_process(lut, inputs, OCIO::INTERP_LINEAR), expected);
                std::printf("[lut accuracy] %-10s %-5s %3d^3 shaper %-6s tetrahedral max %.5f mean %.6f | trilinear "
                            "max %.5f mean %.6f | %8.1f KiB\n",
                            input, clf ? ".clf" : ".cube", cube,
                            clf ? "Log" : (std::string(input) == "ACEScct" ? "none" : std::to_string(shaper).c_str()),
                            tet.max, tet.mean, tri.max, tri.mean, (double)fs::file_size(lut) / 1024.0);
            }
        }
    }
}

TEST_CASE("the scan result is read as Cineon Log, whatever the output", "[ocio][convert]") {
    ColorConverter converter(embedded_active_config());
    const ResultEncoding scan = ResultEncoding::cineon_log;
    // Kodak's reference white (code 685) and black (code 95) decode to 1 and 0, as the
    // embedded config's own Cineon Log space does.
    const std::array<float, 3> codes = {685.0f / 1023, 95.0f / 1023, 0.5f};
    const auto linear = convert(*converter.from_working("lin_rec709", scan), codes);
    const auto reference = convert(*converter.to_working("Cineon Log"), codes);
    CHECK(linear[0] == Approx(1.0).margin(1e-5));
    CHECK(linear[1] == Approx(0.0).margin(1e-5));
    for (int c = 0; c < 3; ++c) CHECK(linear[c] == Approx(reference[c]).margin(1e-6));
    // To Cineon Log itself: decode then encode cancel, so nothing is done.
    CHECK(converter.from_working("Cineon Log", scan)->is_noop());
    // To a display: the display of the decoded values.
    const auto shown = convert(*converter.to_display("sRGB", "Standard", scan), codes);
    const auto shown_linear = convert(*converter.to_display("sRGB", "Standard"), linear);
    for (int c = 0; c < 3; ++c) CHECK(shown[c] == Approx(shown_linear[c]).margin(1e-6));
    // Cached apart from the working-space conversions of the same names.
    CHECK(converter.from_working("lin_rec709", scan) != converter.from_working("lin_rec709"));
    CHECK(converter.from_working("lin_rec709")->is_noop());
    // Data destinations take the scan as it is.
    CHECK(converter.from_working("Raw", scan)->is_noop());
    CHECK(converter.to_display("sRGB", "Raw", scan)->is_noop());
}

TEST_CASE("the embedded config written out is the same config", "[ocio][config]") {
    TempDir dir;
    const std::string path = dir.file("darkroom.ocio");
    std::ofstream(path) << embedded_config_yaml();
    ScopedOcioVariable unset(std::nullopt);
    const ActiveConfig written = resolve_config(path);
    CHECK(std::string(written.config->getName()) == std::string(embedded_config()->getName()));
    CHECK(color_space_names(*written.config) == color_space_names(*embedded_config()));
}

TEST_CASE("every output of the embedded config keeps the model's results finite", "[ocio][convert]") {
    // The model's results are finite and non-negative (docs/guides/command-line.md, bad pixels). Working-space
    // values: black, white, a saturated primary and the 1e30 clamp. Scan codes / 1023: 0 up
    // to 2 (code 2046: (2046 - 95) x 0.002 = 3.9 density above the base).
    ColorConverter converter(embedded_active_config());
    const std::vector<float> working = {0, 0, 0, 1, 1, 1, 1, 0, 0, 1e30f, 1e30f, 1e30f};
    const std::vector<float> scan = {0, 0, 0, 1, 1, 1, 2, 0, 0, 2, 2, 2};
    for (ResultEncoding source : {ResultEncoding::working_linear, ResultEncoding::cineon_log}) {
        auto all_finite = [&](const Conversion& c) {
            std::vector<float> v = source == ResultEncoding::cineon_log ? scan : working;
            c.apply_rgb(v.data(), v.size() / 3);
            return std::all_of(v.begin(), v.end(), [](float x) { return std::isfinite(x); });
        };
        for (const std::string& cs : color_space_names(*embedded_config())) {
            INFO(cs);
            CHECK(all_finite(*converter.from_working(cs, source)));
        }
        for (const std::string& display : display_names(*embedded_config()))
            for (const std::string& view : view_names(*embedded_config(), display)) {
                INFO(display << " / " << view);
                CHECK(all_finite(*converter.to_display(display, view, source)));
            }
    }
}
