// The fault suite: the program run as a pipeline runs it, on bad inputs and in bad
// conditions (layered and odd-shaped files, corrupt and huge ones, settings at and past their
// limits, signals a wrapper ignores, full disks, writers racing). Each case ends in a result
// or a named refusal with its documented exit status, never a crash, a hang or wrong pixels.
#include <OpenImageIO/imageio.h>
#include <chrono>
#include <cstring>
#include <csignal>
#include <nlohmann/json.hpp>
#include <sys/mount.h>
#include <thread>
#include <unistd.h>

#include "cli_support.h"

using namespace darkroom_test;

namespace {

fs::path fresh_dir(const std::string& name) {
    fs::path dir = kTmp / "faults" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

const std::string kLook = " --seed 7 --frame-width-mm 3 --print-width-mm 20 --threads 1";

// A 16x12 file of the named channels, each of its own type; a channel's value at (x, y) is
// 0.1 k + 0.001 x + 1e-7 y, k by its name without the layer (R 1, G 2, B 3, ...), the last term
// one that half cannot hold, to see float kept float.
std::string layered_file(const fs::path& dir, const std::string& name, const std::vector<std::string>& channels,
                         const std::vector<OIIO::TypeDesc>& types) {
    OIIO::ImageSpec spec(16, 12, int(channels.size()), OIIO::TypeDesc::FLOAT);
    spec.channelnames = channels;
    spec.channelformats = types;
    spec.alpha_channel = spec.z_channel = -1;
    std::vector<float> px(16 * 12 * channels.size());
    for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 16; ++x)
            for (size_t c = 0; c < channels.size(); ++c)
                px[(y * 16 + x) * channels.size() + c] =
                    0.1f * float(std::string("RGBAZY").find(channels[c].back()) + 1) + 0.001f * x + 1e-7f * y;
    const std::string path = (dir / name).string();
    auto out = OIIO::ImageOutput::create(path);
    REQUIRE(out);
    REQUIRE(out->open(path, spec));
    REQUIRE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    REQUIRE(out->close());
    return path;
}

// A channel of a file by name, as float, with its stored type.
std::vector<float> channel(const std::string& path, const std::string& name, OIIO::TypeDesc* type = nullptr) {
    auto in = OIIO::ImageInput::open(path);
    REQUIRE(in);
    const OIIO::ImageSpec& s = in->spec();
    const auto at = std::find(s.channelnames.begin(), s.channelnames.end(), name);
    REQUIRE(at != s.channelnames.end());
    const int c = int(at - s.channelnames.begin());
    if (type) *type = s.channelformat(c);
    std::vector<float> out(size_t(s.width) * s.height);
    REQUIRE(in->read_image(0, 0, c, c + 1, OIIO::TypeDesc::FLOAT, out.data()));
    return out;
}

}  // namespace

// Layered EXRs (a render's AOVs): the developed layer is chosen by name, and every other
// channel comes out under its own name, with its own type, bit for bit.
TEST_CASE("faults: a layered EXR develops its colour layer and passes the others through bit for bit",
          "[cli][faults][layers]") {
    const fs::path dir = fresh_dir("layers");
    const OIIO::TypeDesc half = OIIO::TypeDesc::HALF, flt = OIIO::TypeDesc::FLOAT;
    // OpenImageIO lists them so: depth first, the colour after it.
    const std::string aovs = layered_file(dir, "aovs.exr", {"depth.Z", "diffuse.R", "diffuse.G", "diffuse.B"},
                                          {flt, half, half, half});
    const std::string alone = layered_file(dir, "alone.exr", {"diffuse.R", "diffuse.G", "diffuse.B"}, {half, half, half});
    const std::string out = (dir / "out.exr").string(), out_alone = (dir / "out-alone.exr").string();
    Result r = darkroom("develop " + aovs + " -o " + out + kLook);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    REQUIRE(darkroom("develop " + alone + " -o " + out_alone + kLook).exit_code == 0);
    OIIO::TypeDesc type;
    CHECK(channel(out, "depth.Z", &type) == channel(aovs, "depth.Z"));
    CHECK(type == flt);
    for (const char* c : {"diffuse.R", "diffuse.G", "diffuse.B"}) {
        CHECK(channel(out, c, &type) == channel(out_alone, c));
        CHECK(type == half);
    }

    // A beauty with its AOVs: the unnamed RGBA develops, the specular layer passes through.
    const std::string beauty = layered_file(
        dir, "beauty.exr", {"R", "G", "B", "A", "specular.R", "specular.G", "specular.B", "depth.Z"},
        {half, half, half, half, half, half, half, flt});
    REQUIRE(darkroom("develop " + beauty + " -o " + out + kLook).exit_code == 0);
    for (const char* c : {"A", "specular.R", "specular.G", "specular.B", "depth.Z"})
        CHECK(channel(out, c) == channel(beauty, c));
    CHECK(channel(out, "R") != channel(beauty, "R"));
}

TEST_CASE("faults: a file with several colour layers needs --layer, and the error lists them",
          "[cli][faults][layers]") {
    const fs::path dir = fresh_dir("layer-choice");
    const OIIO::TypeDesc half = OIIO::TypeDesc::HALF;
    const std::string two = layered_file(dir, "two.exr", {"diffuse.R", "diffuse.G", "diffuse.B", "specular.R",
                                                          "specular.G", "specular.B"},
                                         std::vector<OIIO::TypeDesc>(6, half));
    const std::string out = (dir / "out.exr").string();
    Result r = darkroom("develop " + two + " -o " + out + kLook);
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("--layer") && Catch::Contains("'diffuse'") && Catch::Contains("'specular'"));
    CHECK_FALSE(fs::exists(out));

    r = darkroom("develop " + two + " -o " + out + kLook + " --layer specular");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    for (const char* c : {"diffuse.R", "diffuse.G", "diffuse.B"}) CHECK(channel(out, c) == channel(two, c));
    CHECK(channel(out, "specular.R") != channel(two, "specular.R"));

    r = darkroom("develop " + two + " -o " + out + kLook + " --layer spec");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("no such layer") && Catch::Contains("'specular'"));

    // A grey layer develops to that layer's R, G, B; its depth passes through.
    const std::string grey = layered_file(dir, "grey.exr", {"depth.Z", "matte.Y"}, {OIIO::TypeDesc::FLOAT, half});
    r = darkroom("develop " + grey + " -o " + out + kLook);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK(channel(out, "depth.Z") == channel(grey, "depth.Z"));
    CHECK(channel(out, "matte.B").size() == 16 * 12);
}

namespace {

// One part of a multi-part test file: its channels and their types, its data window in the
// 16x12 frame, its compression. Float channels hold layered_file's values; uint32 ones
// 2^24 + 1 + 1000003 x + 7 y, which float cannot hold.
struct TestPart {
    std::string name;
    std::vector<std::string> channels;
    std::vector<OIIO::TypeDesc> types;
    int x = 0, y = 0, width = 16, height = 12;
    std::string compression = "zip";
};

std::string multi_part_file(const fs::path& dir, const std::string& name, const std::vector<TestPart>& parts) {
    std::vector<OIIO::ImageSpec> specs;
    for (const TestPart& p : parts) {
        OIIO::ImageSpec spec(p.width, p.height, int(p.channels.size()), OIIO::TypeDesc::FLOAT);
        spec.x = p.x;
        spec.y = p.y;
        spec.full_width = 16;
        spec.full_height = 12;
        spec.channelnames = p.channels;
        spec.channelformats = p.types;
        spec.alpha_channel = spec.z_channel = -1;
        if (!p.name.empty()) spec.attribute("oiio:subimagename", p.name);
        spec.attribute("compression", p.compression);
        specs.push_back(spec);
    }
    const std::string path = (dir / name).string();
    auto out = OIIO::ImageOutput::create(path);
    REQUIRE(out);
    REQUIRE(out->open(path, int(specs.size()), specs.data()));
    for (size_t p = 0; p < parts.size(); ++p) {
        const OIIO::ImageSpec& spec = specs[p];
        std::vector<unsigned char> stored(spec.image_bytes(true));
        unsigned char* to = stored.data();
        for (int y = spec.y; y < spec.y + spec.height; ++y)
            for (int x = spec.x; x < spec.x + spec.width; ++x)
                for (int c = 0; c < spec.nchannels; ++c) {
                    const OIIO::TypeDesc type = spec.channelformat(c);
                    const uint32_t id = (1u << 24) + 1 + 1000003u * x + 7u * y;
                    const float value = 0.1f * float(std::string("RGBAZY").find(spec.channelnames[c].back()) + 1) +
                                        0.001f * x + 1e-7f * y;
                    if (type == OIIO::TypeDesc::UINT)
                        std::memcpy(to, &id, sizeof id);
                    else
                        OIIO::convert_pixel_values(OIIO::TypeDesc::FLOAT, &value, type, to);
                    to += type.size();
                }
        REQUIRE((p == 0 || out->open(path, spec, OIIO::ImageOutput::AppendSubimage)));
        REQUIRE(out->write_image(OIIO::TypeDesc::UNKNOWN, stored.data()));
    }
    REQUIRE(out->close());
    return path;
}

// A channel of a part ("": the first) as the file stores it: its bytes, type, data window and
// compression.
struct StoredChannel {
    std::vector<unsigned char> bytes;
    std::string type, window, compression;
    bool operator==(const StoredChannel& o) const {
        return bytes == o.bytes && type == o.type && window == o.window && compression == o.compression;
    }
};

StoredChannel stored_channel(const std::string& path, const std::string& part, const std::string& name) {
    auto in = OIIO::ImageInput::open(path);
    REQUIRE(in);
    for (int p = 0; in->seek_subimage(p, 0); ++p) {
        const OIIO::ImageSpec s = in->spec();
        if (!part.empty() && s.get_string_attribute("oiio:subimagename") != part) continue;
        const auto at = std::find(s.channelnames.begin(), s.channelnames.end(), name);
        REQUIRE(at != s.channelnames.end());
        const int c = int(at - s.channelnames.begin());
        StoredChannel out{std::vector<unsigned char>(s.image_pixels() * s.channelformat(c).size()),
                          s.channelformat(c).c_str(),
                          std::to_string(s.x) + "," + std::to_string(s.y) + "," + std::to_string(s.width) + "x" +
                              std::to_string(s.height),
                          s.get_string_attribute("compression")};
        REQUIRE(in->read_image(p, 0, c, c + 1, s.channelformat(c), out.bytes.data()));
        return out;
    }
    FAIL("'" << path << "' has no part '" << part << "'");
    return {};
}

std::vector<std::string> part_names(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    REQUIRE(in);
    std::vector<std::string> names;
    for (int p = 0; in->seek_subimage(p, 0); ++p) names.push_back(in->spec().get_string_attribute("oiio:subimagename"));
    return names;
}

const OIIO::TypeDesc kHalf = OIIO::TypeDesc::HALF, kFloat = OIIO::TypeDesc::FLOAT, kUint = OIIO::TypeDesc::UINT;

// A beauty part (RGBA half, an object ID, a float depth), a diffuse part of its own smaller data
// window and compression, and a part of IDs alone.
std::vector<TestPart> render_parts() {
    return {{"beauty", {"R", "G", "B", "A", "id", "depth.Z"}, {kHalf, kHalf, kHalf, kHalf, kUint, kFloat}},
            {"diffuse", {"diffuse.R", "diffuse.G", "diffuse.B"}, {kHalf, kHalf, kFloat}, 4, 3, 8, 6, "piz"},
            {"ids", {"crypto.id", "crypto.coverage"}, {kUint, kFloat}, 2, 1, 12, 10, "rle"}};
}

}  // namespace

// Multi-part EXRs: the layer to develop is chosen among every part's layers, developed in its
// part, and every other part and channel is written under its own name, type, part, data
// window and compression, bit for bit.
TEST_CASE("faults: a multi-part EXR develops its layer in its part and passes the rest through bit for bit",
          "[cli][faults][layers][parts]") {
    const fs::path dir = fresh_dir("multi-part");
    const std::vector<TestPart> parts = render_parts();
    const std::string in = multi_part_file(dir, "render.exr", parts), out = (dir / "out.exr").string();
    auto passes_through = [&](const std::string& output, const TestPart& part) {
        for (const std::string& c : part.channels) {
            INFO(part.name << " " << c);
            CHECK(stored_channel(output, part.name, c) == stored_channel(in, part.name, c));
        }
    };

    // By default the unnamed colour (of the beauty part) develops; its alpha, ID and depth pass
    // through, and so do the other parts.
    Result r = darkroom("develop " + in + " -o " + out + kLook);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK(part_names(out) == std::vector<std::string>{"beauty", "diffuse", "ids"});
    for (const char* c : {"A", "id", "depth.Z"}) {
        INFO(c);
        CHECK(stored_channel(out, "beauty", c) == stored_channel(in, "beauty", c));
    }
    CHECK(stored_channel(out, "beauty", "R").bytes != stored_channel(in, "beauty", "R").bytes);
    passes_through(out, parts[1]);
    passes_through(out, parts[2]);
    // -d sets the picture's precision; an object ID stays uint32, exactly.
    REQUIRE(darkroom("develop " + in + " -o " + out + " -d float" + kLook).exit_code == 0);
    CHECK(stored_channel(out, "beauty", "id") == stored_channel(in, "beauty", "id"));
    CHECK(stored_channel(out, "beauty", "R").type == "float");

    // --layer by a part's name: the diffuse part develops in its own data window as the same
    // layer alone in a file would; the beauty and ID parts pass through whole.
    const std::string alone = multi_part_file(dir, "diffuse.exr", {parts[1]}), out_alone = (dir / "alone.exr").string();
    r = darkroom("develop " + in + " -o " + out + " --layer diffuse" + kLook);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    REQUIRE(darkroom("develop " + alone + " -o " + out_alone + kLook).exit_code == 0);
    CHECK(part_names(out) == std::vector<std::string>{"beauty", "diffuse", "ids"});
    passes_through(out, parts[0]);
    passes_through(out, parts[2]);
    for (const char* c : {"diffuse.R", "diffuse.G", "diffuse.B"}) {
        INFO(c);
        CHECK(stored_channel(out, "diffuse", c) == stored_channel(out_alone, "diffuse", c));
        CHECK(stored_channel(out, "diffuse", c).bytes != stored_channel(in, "diffuse", c).bytes);
        CHECK(stored_channel(out, "diffuse", c).window == "4,3,8x6");
    }

    // grain apply puts the grain on the chosen layer and passes the rest through the same way.
    {
        std::ofstream profile((dir / "grain.json").string());
        profile << R"({"format": "darkroom-grain-profile", "version": 1, "encoding": "linear", "channels": [)";
        for (const char* c : {"R", "G", "B"})
            profile << (c[0] == 'R' ? "" : ", ") << R"({"name": ")" << c
                    << R"(", "response": {"level": [0.1, 0.9], "sigma": [0.01, 0.02]},)"
                    << R"( "autocorrelation": {"radius": 1, "values": [0, 0.2, 0, 0.2, 1, 0.2, 0, 0.2, 0]}})";
        profile << R"(], "channel_correlation": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]})";
    }
    r = darkroom("grain apply " + in + " --profile " + (dir / "grain.json").string() + " -o " + out +
                 " --layer diffuse --seed 3");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    passes_through(out, parts[0]);
    passes_through(out, parts[2]);
    CHECK(stored_channel(out, "diffuse", "diffuse.G").bytes != stored_channel(in, "diffuse", "diffuse.G").bytes);

    // grain analyze measures the chosen layer: the diffuse part is 8x6, the beauty 16x12 (both
    // too small to measure, which says which was read).
    r = darkroom("grain analyze " + in + " --layer diffuse --block-size 8 -o " + (dir / "plate.json").string());
    CHECK_THAT(r.output, Catch::Contains("8x6 pixels"));
    r = darkroom("grain analyze " + in + " --block-size 8 -o " + (dir / "plate.json").string());
    CHECK_THAT(r.output, Catch::Contains("16x12 pixels"));
    r = darkroom("grain analyze " + in + " --layer crypto --block-size 8 -o " + (dir / "plate.json").string());
    CHECK_THAT(r.output, Catch::Contains("--layer 'crypto'") && Catch::Contains("has no colour channels"));
}

// uint32 channels (object IDs) in a file of one part: kept exactly in OpenEXR; any other format
// holds one type for all its channels, and the run says the IDs are not kept.
TEST_CASE("faults: uint32 channels pass through exactly, or are named where the format cannot keep them",
          "[cli][faults][layers]") {
    const fs::path dir = fresh_dir("uint32");
    const std::string in = multi_part_file(dir, "ids.exr", {{"", {"R", "G", "B", "id"}, {kHalf, kHalf, kHalf, kUint}}});
    const std::string out = (dir / "out.exr").string();
    Result r = darkroom("develop " + in + " -o " + out + kLook);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK(stored_channel(out, "", "id") == stored_channel(in, "", "id"));
    CHECK(stored_channel(out, "", "id").type == "uint");
    for (const std::string flags : {"", " -n"}) {
        r = darkroom("develop " + in + " -o " + (dir / "out.tif").string() + kLook + flags);
        INFO(flags << "\n" << r.output);
        CHECK(r.exit_code == 0);
        CHECK_THAT(r.output, Catch::Contains("uint32 channel 'id'") && Catch::Contains(".exr"));
    }
    r = darkroom("develop " + in + " -o " + out + kLook);
    CHECK(r.output.find("uint32") == std::string::npos);
}

TEST_CASE("faults: a layer that several parts could give is named, and a single-part format refused",
          "[cli][faults][layers][parts]") {
    const fs::path dir = fresh_dir("part-choice");
    const std::vector<TestPart> two{{"left", {"R", "G", "B"}, {kHalf, kHalf, kHalf}},
                                    {"right", {"R", "G", "B"}, {kHalf, kHalf, kHalf}}};
    const std::string in = multi_part_file(dir, "stereo.exr", two), out = (dir / "out.exr").string();
    Result r = darkroom("develop " + in + " -o " + out + kLook);
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("--layer") && Catch::Contains("(unnamed) of part 'left'") &&
                             Catch::Contains("(unnamed) of part 'right'"));
    CHECK_FALSE(fs::exists(out));
    r = darkroom("develop " + in + " -o " + out + kLook + " --layer centre");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("no such layer or part") && Catch::Contains("of part 'right'"));

    r = darkroom("develop " + in + " -o " + out + kLook + " --layer right");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    for (const char* c : {"R", "G", "B"}) {
        CHECK(stored_channel(out, "left", c) == stored_channel(in, "left", c));
        CHECK(stored_channel(out, "right", c).bytes != stored_channel(in, "right", c).bytes);
    }

    // Only OpenEXR holds several parts: any other output is refused before the work, a dry run
    // says so too, and a layer of one part alone is not enough.
    const std::string render = multi_part_file(dir, "render.exr", render_parts());
    for (const std::string output : {"out.tif", "out.png", "out.dpx"})
        for (const std::string& flags : {std::string(), std::string(" --layer diffuse"), std::string(" -n")}) {
            r = darkroom("develop " + render + " -o " + (dir / output).string() + kLook + flags);
            INFO(output << flags << "\n" << r.output);
            CHECK(r.exit_code == (flags == " -n" ? 0 : 1));
            CHECK_THAT(r.output, Catch::Contains("has 3 parts") && Catch::Contains(".exr"));
            CHECK_FALSE(fs::exists(dir / output));
        }

    // A sequence of multi-part frames: each frame's parts, through the overlapped writer.
    for (const char* frame : {"1001", "1002"}) fs::copy_file(render, dir / ("seq." + std::string(frame) + ".exr"));
    r = darkroom("develop " + (dir / "seq.####.exr").string() + " -o " + (dir / "dev.####.exr").string() +
                 " --frames 1001-1002 --seed 7 --frame-width-mm 3 --print-width-mm 20");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    for (const char* frame : {"1001", "1002"}) {
        const std::string developed = (dir / ("dev." + std::string(frame) + ".exr")).string();
        CHECK(part_names(developed) == std::vector<std::string>{"beauty", "diffuse", "ids"});
        CHECK(stored_channel(developed, "ids", "crypto.id") == stored_channel(render, "ids", "crypto.id"));
    }
}

// A farm wrapper or nohup ignores SIGHUP (or SIGINT) for the program it starts: it runs on.
TEST_CASE("faults: a signal ignored by the caller stays ignored", "[cli][faults][signals]") {
    const fs::path dir = fresh_dir("inherited-signals");
    const std::string in = make_input("faults-signal-plate.exr", 96, 72);
    for (int signal_number : {SIGHUP, SIGINT}) {
        INFO("signal " << signal_number);
        const std::string out = (dir / "still.####.exr").string();
        for (const auto& entry : fs::directory_iterator(dir)) fs::remove(entry.path());
        const std::string trap = signal_number == SIGHUP ? "HUP" : "INT";
        pid_t pid = fork();
        REQUIRE(pid >= 0);
        if (pid == 0) {
            const std::string command = "trap '' " + trap + "; exec " + std::string(DARKROOM_EXE) + " develop " + in +
                                        " -o " + out + " --frames 1-6 -q --frames-at-once 1" + kLook;
            execl("/bin/sh", "sh", "-c", command.c_str(), (char*)nullptr);
            _exit(127);
        }
        int status = 0;
        bool exited = false;
        const char* first = "still.0001.exr";
        while (!fs::exists(dir / first) && !exited) {
            exited = waitpid(pid, &status, WNOHANG) == pid;
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
        if (!exited) {
            kill(pid, signal_number);
            waitpid(pid, &status, 0);
        }
        REQUIRE(WIFEXITED(status));
        CHECK(WEXITSTATUS(status) == 0);
        CHECK(fs::exists(dir / "still.0006.exr"));
    }
    // Not ignored, it stops the run as before.
    const std::string out = (dir / "stopped.####.exr").string();
    pid_t pid = fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
        const std::string command = "exec " + std::string(DARKROOM_EXE) + " develop " + in + " -o " + out +
                                    " --frames 1-200 -q --frames-at-once 1" + kLook;
        execl("/bin/sh", "sh", "-c", command.c_str(), (char*)nullptr);
        _exit(127);
    }
    while (!fs::exists(dir / "stopped.0001.exr")) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    kill(pid, SIGHUP);
    int status = 0;
    waitpid(pid, &status, 0);
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 128 + SIGHUP);
    CHECK(temp_files_in(dir) == 0);
}

// Each writer's limits are checked before the work: DPX's writer aborts on more than 4
// channels, the others drop channels or change the type without a word.
TEST_CASE("faults: an output format that cannot hold the channels or the type is refused before the work",
          "[cli][faults][formats]") {
    const fs::path dir = fresh_dir("formats");
    const OIIO::TypeDesc half = OIIO::TypeDesc::HALF;
    const std::string five =
        layered_file(dir, "five.exr", {"R", "G", "B", "A", "Z"}, std::vector<OIIO::TypeDesc>(5, half));
    const std::string rgb = layered_file(dir, "rgb.exr", {"R", "G", "B"}, std::vector<OIIO::TypeDesc>(3, half));
    struct Case {
        std::string input, output, flags, message;
    };
    for (const Case& c : std::vector<Case>{
             {five, "five.dpx", "", "DPX holds 1, 3, 4 channels, and the output has 5"},
             {five, "five.png", "", "PNG holds 1, 2, 3, 4 channels"},
             {five, "five.hdr", "", "Radiance HDR holds 3 channels"},
             {five, "five.jpg", "", "JPEG holds 1, 3 channels"},
             {rgb, "out.exr", " -d uint16", "-d uint16: OpenEXR"},
             {rgb, "rgb.png", " -d half", "-d half: PNG"},
             {rgb, "rgb.jpg", " -d uint16", "-d uint16: JPEG"},
             {rgb, "rgb.hdr", " -d half", "-d half: Radiance HDR"},
             {rgb, "rgb.dpx", " -d half", "-d half: DPX"},
         }) {
        const std::string out = (dir / c.output).string();
        for (const std::string& dry : std::vector<std::string>{"", " -n"}) {
            Result r = darkroom("develop " + c.input + " -o " + out + c.flags + kLook + dry);
            INFO(c.output << c.flags << dry << "\n" << r.output);
            CHECK(r.exit_code == (dry.empty() || !c.flags.empty() ? 1 : 0));
            CHECK_THAT(r.output, Catch::Contains(c.message));
            CHECK_FALSE(fs::exists(out));
        }
    }
    // What they hold is written.
    for (const char* ok : {"rgb.dpx", "rgb.png", "rgb.hdr", "rgb.jpg", "rgb.tif"})
        CHECK(darkroom("develop " + rgb + " -o " + (dir / ok).string() + kLook).exit_code == 0);
    CHECK(darkroom("develop " + five + " -o " + (dir / "five.tif").string() + kLook).exit_code == 0);
}

// Settings and files at and past their limits: each refused before the work, naming what to
// change, with the status its kind of problem has (docs/reference/exit-codes.md).
TEST_CASE("faults: flags, files and sizes past their limits are refused before the work", "[cli][faults][limits]") {
    const fs::path dir = fresh_dir("limits");
    const std::string in = make_input("faults-limits.exr", 64, 64), out = (dir / "out.exr").string();
    std::ofstream((dir / "corrupt.exr").string()) << "v/1\x01 not an image";
    {
        std::ofstream big((dir / "big.json").string());
        big << "{\"format\": \"darkroom-look\", \"version\": 1, \"settings\": {}, \"pad\": \"";
        big << std::string(17u << 20, 'x') << "\"}";
    }
    // A header that promises 36000x36000 pixels (73 GB to develop) over a few bytes of them.
    std::ofstream((dir / "huge.ppm").string(), std::ios::binary) << "P6\n36000 36000\n255\n" << std::string(300, '\0');
    std::ofstream((dir / "both.json").string())
        << R"({"format": "darkroom-look", "version": 1, "settings": {"tocolorspace": "ACEScg", "ociodisplay": ["sRGB", ""]}})";
    struct Case {
        std::string args, message;
        int exit_code;
    };
    const std::string develop = "develop " + in + " -o " + out;
    for (const Case& c : std::vector<Case>{
             {"develop " + in + " -o " + (dir / "o.####.exr").string() + " --frames 1-100000000 -n",
              "more than 1000000 frames", 1},
             {develop + " --grain-size 100 --halation 0 --frame-width-mm 0.0064", "the grain of film layer", 1},
             {develop + " --frame-width-mm 0.0064", "the halation of film layer", 1},
             {develop + " --look " + (dir / "big.json").string(), "more than the 16 MB a look file may be", 1},
             {develop + " --film " + (dir / "big.json").string(), "more than the 16 MB a stock file may be", 1},
             {develop + " --grain-profile " + (dir / "big.json").string(), "more than the 16 MB a grain profile may be", 1},
             {develop + " --look " + (dir / "both.json").string(), "both say where the result goes", 1},
             {"develop " + (dir / "corrupt.exr").string() + " -o " + out, "cannot read", 1},
             {"develop " + (dir / "huge.ppm").string() + " -o " + out, "GB of memory", 1},
             {develop + " --log " + (dir / "no-folder" / "log.json").string(), "does not exist", 1},
             {develop + " --window 0,0,2147483647,5", "is not inside the 64x64 image", 1},
             {develop + " --seed 18446744073709551616", "--seed: must be a whole number", 105},
             {develop + " --seed -1", "--seed: must be a whole number", 104},
             {develop + " --exposure 65", "--exposure: must be a number from -64 to 64", 105},
             {develop + " --exposure lots", "--exposure: must be a number", 104},
         }) {
        Result r = darkroom(c.args);
        INFO(c.args << "\n" << r.output);
        CHECK(r.exit_code == c.exit_code);
        CHECK_THAT(r.output, Catch::Contains(c.message));
        CHECK_FALSE(fs::exists(out));
    }
}

// A seed above 2^63 is kept exactly in the image's metadata, as in look files.
TEST_CASE("faults: a 64-bit seed is kept exactly in the output's metadata", "[cli][faults][limits]") {
    const fs::path dir = fresh_dir("seed");
    const std::string in = make_input("faults-seed.exr", 16, 12), out = (dir / "out.exr").string();
    const std::string seed = "18446744073709551615";
    Result r = darkroom("develop " + in + " -o " + out + " --seed " + seed + " --save-look " + (dir / "look.json").string());
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    auto file = OIIO::ImageInput::open(out);
    REQUIRE(file);
    const nlohmann::json look = nlohmann::json::parse(file->spec().get_string_attribute("darkroom:look"));
    CHECK(look["settings"]["seed"].get<uint64_t>() == 18446744073709551615ull);
    CHECK_THAT(file_bytes(dir / "look.json"), Catch::Contains(seed));
}

// A full disk: the write fails with a message naming the output, the partial temporary is
// removed, nothing is left under the output's name, and the input is untouched. Needs a small
// tmpfs, which a test running as root (CI) mounts itself; elsewhere it says so and passes by.
TEST_CASE("faults: a full disk fails the frame with a message and leaves no partial output", "[cli][faults][disk]") {
    const fs::path dir = fresh_dir("disk-full"), small = dir / "small";
    fs::create_directories(small);
    if (::mount("tmpfs", small.c_str(), "tmpfs", 0, "size=64k") != 0) {
        WARN("cannot mount a small tmpfs here (not root?): the full-disk case is not run");
        return;
    }
    struct Unmount {
        fs::path at;
        ~Unmount() { ::umount(at.c_str()); }
    } unmount{small};
    // 512x512 float RGB without compression: 3 MB, far past the 64 KB the disk holds.
    const std::string in = make_input("faults-disk-in.exr", 512, 512);
    const std::string before = file_bytes(in);
    for (const std::string& out : {(small / "out.exr").string(), (small / "seq.####.exr").string()}) {
        INFO(out);
        const std::string frames = out.find('#') != std::string::npos ? " --frames 1-2" : "";
        const Result r = darkroom("develop " + in + " -o " + out + frames + " -d float --compression none" + kLook);
        INFO(r.output);
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.output, Catch::Contains("cannot write") && Catch::Contains(small.string()));
        CHECK(fs::is_empty(small));  // no temporary, no partial frame
    }
    CHECK(file_bytes(in) == before);
}

// Two runs writing the same outputs at once (a farm that started a chunk twice): each output
// is one run's whole frame, never a mix or a torn file, because each run writes its own
// temporary and renames it over the output.
TEST_CASE("faults: two runs writing the same frames at once leave whole frames", "[cli][faults][concurrent]") {
    const fs::path dir = fresh_dir("concurrent");
    const std::string in = make_input("faults-concurrent-in.exr", 96, 64);
    const std::string out = (dir / "film.####.exr").string();
    const std::string command = std::string(DARKROOM_EXE) + " develop " + in + " -o " + out + " --frames 1-8" + kLook;
    const Result both = shell("(" + command + " --exposure 1 & " + command + " --exposure -1 & wait)");
    INFO(both.output);
    // The whole frames of each run, one at a time, to compare with.
    const fs::path one = dir / "one", two = dir / "two";
    fs::create_directories(one);
    fs::create_directories(two);
    REQUIRE(darkroom("develop " + in + " -o " + (one / "film.####.exr").string() + " --frames 1-8 --exposure 1" + kLook)
                .exit_code == 0);
    REQUIRE(darkroom("develop " + in + " -o " + (two / "film.####.exr").string() + " --frames 1-8 --exposure -1" + kLook)
                .exit_code == 0);
    for (int frame = 1; frame <= 8; ++frame) {
        char name[32];
        std::snprintf(name, sizeof name, "film.%04d.exr", frame);
        INFO(name);
        // (Pixels: each file's metadata names its own command line.)
        const std::vector<float> got = pixels((dir / name).string());
        CHECK((got == pixels((one / name).string()) || got == pixels((two / name).string())));
    }
    for (const auto& entry : fs::directory_iterator(dir))  // no temporaries left behind
        CHECK(entry.path().filename().string().rfind(".darkroom-tmp", 0) != 0);
}
