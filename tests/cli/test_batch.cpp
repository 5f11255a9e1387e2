// Batch work the oiiotool way: sequences, look files, metadata, safe writes, resuming.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <nlohmann/json.hpp>
#include <thread>
#include <unistd.h>

#include "cli_support.h"

using namespace darkroom_test;

namespace {

fs::path fresh_dir(const std::string& name) {
    fs::path dir = kTmp / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

// Writes the same plate as frames `first`..`last` of "<dir>/plate.%04d.exr".
void make_plates(const fs::path& dir, int first, int last, int w = 40, int h = 30) {
    std::string plate = make_input("plate-source.exr", w, h);
    char name[64];
    for (int f = first; f <= last; ++f) {
        std::snprintf(name, sizeof name, "plate.%04d.exr", f);
        fs::copy_file(plate, dir / name, fs::copy_options::overwrite_existing);
    }
}

std::string frame_name(const fs::path& dir, const char* stem, int frame) {
    char name[64];
    std::snprintf(name, sizeof name, "%s.%04d.exr", stem, frame);
    return (dir / name).string();
}

const std::string kLook = " --seed 11 --frame-width-mm 3 --print-width-mm 20";

// "<dir>/nan.exr": a 16x12 mid-grey RGB plate whose pixel (3, 4) has a NaN in red.
std::string grey_plate_with_nan(const fs::path& dir) {
    OIIO::ImageBuf plate(OIIO::ImageSpec(16, 12, 3, OIIO::TypeDesc::FLOAT));
    const float grey[3] = {0.18f, 0.18f, 0.18f}, nan[3] = {NAN, 0.18f, 0.18f};
    OIIO::ImageBufAlgo::fill(plate, grey);
    plate.setpixel(3, 4, nan);
    const std::string path = (dir / "nan.exr").string();
    REQUIRE(plate.write(path));
    return path;
}

// How many times `what` occurs in `text`.
size_t count(const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
}

// "<dir>/plate.%04d.exr" for frames 1..`frames`, each its own picture (the gradient at
// another exposure) and frame 1 the largest, so that overlapped frames finish out of order.
void make_distinct_plates(const fs::path& dir, int frames) {
    for (int f = 1; f <= frames; ++f) {
        const int w = f == 1 ? 160 : 48, h = f == 1 ? 120 : 36;
        OIIO::ImageBuf plate(OIIO::ImageSpec(w, h, 3, OIIO::TypeDesc::HALF));
        const float k = 0.25f * f, top[3] = {0.02f * k, 0.05f * k, 0.1f * k}, bottom[3] = {1.5f * k, 0.9f * k, 0.3f * k};
        OIIO::ImageBufAlgo::fill(plate, top, bottom);
        plate.specmod().attribute("compression", "piz");
        REQUIRE(plate.write(frame_name(dir, "plate", f)));
    }
}

// Where the line of each frame of 1..`frames` ("frame N: ..." or, failed, "... frame N (...")
// is in `output`.
std::vector<size_t> frame_line_positions(const std::string& output, int frames) {
    std::vector<size_t> at;
    for (int f = 1; f <= frames; ++f) {
        const std::string frame = "frame " + std::to_string(f);
        at.push_back(std::min(output.find(frame + ":"), output.find(frame + " (")));
    }
    return at;
}

}  // namespace

TEST_CASE("a sequence gives each frame its own grain, the same as a single image of that frame, reproducibly",
          "[cli][batch][determinism]") {
    fs::path dir = fresh_dir("sequence");
    make_plates(dir, 1, 3);
    Result r = darkroom("develop " + (dir / "plate.####.exr").string() + " -o " + (dir / "out.####.exr").string() +
                        kLook + " --threads 2");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    // The plates are identical, so any difference between frames is the grain.
    std::vector<float> f1 = pixels(frame_name(dir, "out", 1)), f2 = pixels(frame_name(dir, "out", 2)),
                       f3 = pixels(frame_name(dir, "out", 3));
    CHECK(f1 != f2);
    CHECK(f2 != f3);
    CHECK(f1 != f3);

    // Frame 2 of the sequence is frame 2 developed on its own, whatever the thread count.
    std::string single = (dir / "single.exr").string();
    REQUIRE(darkroom("develop " + frame_name(dir, "plate", 2) + " -o " + single + kLook + " --frame 2 --threads 1")
                .exit_code == 0);
    CHECK(pixels(single) == f2);

    // Re-running the same command gives the same bytes.
    const std::string first_bytes = file_bytes(frame_name(dir, "out", 3));
    fs::remove(frame_name(dir, "out", 3));
    REQUIRE(darkroom("develop " + (dir / "plate.####.exr").string() + " -o " + (dir / "out.####.exr").string() +
                     kLook + " --threads 2")
                .exit_code == 0);
    CHECK(file_bytes(frame_name(dir, "out", 3)) == first_bytes);
}

TEST_CASE("frames written while the next develops are the frames made one after another, reported in frame order",
          "[cli][batch][determinism]") {
    fs::path dir = fresh_dir("overlap");
    const int frames = 6;
    make_distinct_plates(dir, frames);
    fs::remove(frame_name(dir, "plate", 4));  // a failed frame among them
    const std::string in = (dir / "plate.####.exr").string();
    auto run = [&](const std::string& out, const std::string& how) {
        return darkroom("develop " + in + " -o " + (dir / (out + ".####.exr")).string() + " --frames 1-6" + kLook +
                        " --skip-bad-frames --log " + (dir / (out + ".json")).string() + how);
    };
    const Result in_turn = run("in-turn", " --no-overlap --threads 1");
    const Result overlapped = run("overlapped", " --threads 3 --frames-at-once 3");
    INFO(in_turn.output << overlapped.output);
    REQUIRE(in_turn.exit_code == 1);
    REQUIRE(overlapped.exit_code == 1);
    for (const Result* r : {&in_turn, &overlapped}) {
        CHECK_THAT(r->output, Catch::Contains("frame 4 (") && Catch::Contains("1 of 6 frames failed"));
        const std::vector<size_t> at = frame_line_positions(r->output, frames);
        CHECK(std::find(at.begin(), at.end(), std::string::npos) == at.end());
        CHECK(std::is_sorted(at.begin(), at.end()));
    }
    for (const std::string out : {"in-turn", "overlapped"}) {
        nlohmann::json log = nlohmann::json::parse(file_bytes(dir / (out + ".json")));
        REQUIRE(log["frames"].size() == frames);
        for (int f = 1; f <= frames; ++f) CHECK(log["frames"][f - 1]["frame"] == f);
    }
    CHECK(temp_files_in(dir) == 0);
    CHECK_FALSE(fs::exists(frame_name(dir, "overlapped", 4)));
    // Each frame's own pixels, in the input's type and compression: none taken from another frame.
    for (int f : {1, 2, 3, 5, 6}) {
        INFO("frame " << f);
        const std::vector<float> got = pixels(frame_name(dir, "overlapped", f));
        CHECK(got == pixels(frame_name(dir, "in-turn", f)));
        const OIIO::ImageSpec spec = OIIO::ImageInput::open(frame_name(dir, "overlapped", f))->spec();
        CHECK(spec.format == OIIO::TypeDesc::HALF);
        CHECK(spec.get_string_attribute("compression") == "piz");
        if (f > 1) CHECK(got != pixels(frame_name(dir, "overlapped", f == 2 ? 3 : 2)));
    }
}

// The most frames of a --log's run in flight at once (reading, developing or being written).
int most_frames_in_flight(const nlohmann::json& log) {
    int most = 0;
    for (const auto& f : log["frames"]) {
        int at_once = 0;
        for (const auto& g : log["frames"])
            at_once += g["start_seconds"] <= f["start_seconds"] && f["start_seconds"] < g["end_seconds"];
        most = std::max(most, at_once);
    }
    return most;
}

TEST_CASE("a run holds at most two frames per frame at once: one developing, one being written", "[cli][batch][memory]") {
    fs::path dir = fresh_dir("in-flight");
    const int frames = 8;
    make_plates(dir, 1, frames, 256, 256);
    // Writes slower than the develop (pxr24, the negative alone): an unbounded run would pile them up.
    const std::string args = "develop " + (dir / "plate.####.exr").string() + " -o " + (dir / "out.####.exr").string() +
                             " --compression pxr24 --no-grain --no-mtf --paper none --output negative -q --log " +
                             (dir / "log.json").string();
    for (const auto& [how, most] : {std::pair{" --threads 1 --frames-at-once 1 --no-overlap", 1},
                                    std::pair{" --threads 1 --frames-at-once 1", 2},
                                    std::pair{" --threads 2 --frames-at-once 2", 4}}) {
        INFO(how);
        REQUIRE(darkroom(args + how).exit_code == 0);
        nlohmann::json log = nlohmann::json::parse(file_bytes(dir / "log.json"));
        REQUIRE(log["frames"].size() == frames);
        for (const auto& f : log["frames"]) CHECK(f["start_seconds"] < f["end_seconds"]);
        CHECK(most_frames_in_flight(log) <= most);
        if (most == 2) CHECK(most_frames_in_flight(log) == 2);  // (each write outlasts the next frame's start)
    }
}

TEST_CASE("frame wildcards and ranges follow oiiotool", "[cli][batch]") {
    fs::path dir = fresh_dir("wildcards");
    make_plates(dir, 1, 6, 16, 12);
    const std::string fast = " --no-grain --no-mtf -q";
    struct Case {
        std::string input, output, frames;
        std::vector<int> expected;
    };
    for (const Case& c : std::vector<Case>{
             {"plate.%04d.exr", "a.%04d.exr", "1-5x2", {1, 3, 5}},
             {"plate.@@@@.exr", "b.#.exr", "2,4", {2, 4}},
             {"plate.#.exr", "c.####.exr", "", {1, 2, 3, 4, 5, 6}},  // without --frames: the files on disk
             {"plate.1-2#.exr", "d.#.exr", "", {1, 2}},              // a range in the name
         }) {
        Result r = darkroom("develop " + (dir / c.input).string() + " -o " + (dir / c.output).string() +
                            (c.frames.empty() ? "" : " --frames " + c.frames) + fast);
        INFO(c.input << " -> " << c.output << "\n" << r.output);
        REQUIRE(r.exit_code == 0);
        std::string stem = c.output.substr(0, 1);
        for (int f = 1; f <= 6; ++f) {
            bool wanted = std::find(c.expected.begin(), c.expected.end(), f) != c.expected.end();
            CHECK(fs::exists(frame_name(dir, stem.c_str(), f)) == wanted);
        }
    }
    // --framepadding sets the digits of '#'.
    REQUIRE(darkroom("develop " + (dir / "plate.%04d.exr").string() + " -o " + (dir / "e.#.exr").string() +
                     " --frames 3 --framepadding 2" + fast)
                .exit_code == 0);
    CHECK(fs::exists(dir / "e.03.exr"));
}

TEST_CASE("frames missing from a sequence on disk are named, as ranges, by the run and the dry run",
          "[cli][batch][bad-input]") {
    fs::path dir = fresh_dir("gaps");
    make_plates(dir, 1, 12, 8, 6);
    for (int f : {6, 8, 9}) fs::remove(frame_name(dir, "plate", f));
    const std::string in = (dir / "plate.####.exr").string(),
                      args = "develop " + in + " -o " + (dir / "out.####.exr").string() + " --no-grain --no-mtf";
    const std::string warning = "darkroom: warning: the input sequence '" + in +
                                "' has frames 1-12 on disk but not 6, 8-9, which are left out";
    for (const char* flags : {" -n", " -q"}) {
        Result r = darkroom(args + flags);
        INFO(flags << "\n" << r.output);
        CHECK(r.exit_code == 0);
        CHECK(count(r.output, warning) == 1);
    }
    for (int f = 1; f <= 12; ++f) CHECK(fs::exists(frame_name(dir, "out", f)) == (f != 6 && f != 8 && f != 9));
    // Frames named by --frames, or a sequence without gaps, say nothing of it.
    CHECK_THAT(darkroom(args + " -n --frames 1-12").output, !Catch::Contains("on disk but not"));
    make_plates(dir, 6, 9, 8, 6);
    CHECK_THAT(darkroom(args + " -n").output, !Catch::Contains("on disk but not"));
}

TEST_CASE("a missing frame fails with its name and --skip-bad-frames goes on and still reports it", "[cli][batch][bad-input]") {
    fs::path dir = fresh_dir("missing");
    make_plates(dir, 1, 3);
    fs::remove(frame_name(dir, "plate", 2));
    const std::string args = "develop " + (dir / "plate.####.exr").string() + " -o " + (dir / "out.####.exr").string() +
                             " --frames 1-3 --no-grain --no-mtf --threads 1";
    Result r = darkroom(args);
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("plate.0002.exr") && Catch::Contains("does not exist") &&
                             Catch::Contains("frames failed"));
    CHECK_FALSE(fs::exists(frame_name(dir, "out", 2)));

    r = darkroom(args + " --skip-bad-frames --log " + (dir / "log.json").string());
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("1 of 3 frames failed") && Catch::Contains("plate.0002.exr"));
    CHECK(fs::exists(frame_name(dir, "out", 1)));
    CHECK(fs::exists(frame_name(dir, "out", 3)));
    nlohmann::json log = nlohmann::json::parse(file_bytes(dir / "log.json"));
    REQUIRE(log["frames"].size() == 3);
    CHECK(log["summary"]["failed"] == 1);
    for (const auto& f : log["frames"]) {
        CHECK(f["status"] == (f["frame"] == 2 ? "failed" : "developed"));
        if (f["frame"] != 2) CHECK(f["develop_seconds"].get<double>() > 0);
    }
}

TEST_CASE("a run killed halfway leaves only complete frames, logs them, and --no-clobber finishes it",
          "[cli][batch][safe-writes]") {
    fs::path dir = fresh_dir("killed");
    const int frames = 8;
    make_plates(dir, 1, frames, 96, 72);
    const std::string in = (dir / "plate.####.exr").string(), out = (dir / "out.####.exr").string();
    const std::string look = kLook;

    for (int signal_number : {SIGTERM, SIGKILL}) {
        for (int f = 1; f <= frames; ++f) fs::remove(frame_name(dir, "out", f));
        const fs::path interrupted_log = dir / "interrupted.json";
        fs::remove(interrupted_log);
        pid_t pid = fork();
        REQUIRE(pid >= 0);
        if (pid == 0) {
            std::string command = std::string(DARKROOM_EXE) + " develop " + in + " -o " + out + look +
                                  " -q --threads 1 --log " + interrupted_log.string();
            execl("/bin/sh", "sh", "-c", ("exec " + command).c_str(), (char*)nullptr);
            _exit(127);
        }
        // Kill it once the first frame is complete: later frames are in flight or not started.
        int status = 0;
        bool exited = false;
        while (!fs::exists(frame_name(dir, "out", 1)) && !exited) {
            exited = waitpid(pid, &status, WNOHANG) == pid;
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        REQUIRE_FALSE(exited);  // the run failed before its first frame
        kill(pid, signal_number);
        waitpid(pid, &status, 0);
        INFO("signal " << signal_number);
        if (signal_number == SIGTERM) {
            CHECK(WIFEXITED(status));
            CHECK(WEXITSTATUS(status) == 128 + SIGTERM);
            CHECK(temp_files_in(dir) == 0);
        }
        // Every output under its own name is complete.
        int done = 0;
        for (int f = 1; f <= frames; ++f)
            if (fs::exists(frame_name(dir, "out", f))) {
                ++done;
                CHECK(pixels(frame_name(dir, "out", f)).size() == 96 * 72 * 3);
            }
        CHECK(done < frames);
        if (signal_number == SIGTERM) {
            // The log lists the frames finished before the signal, and says it came.
            REQUIRE(fs::exists(interrupted_log));
            nlohmann::json log = nlohmann::json::parse(file_bytes(interrupted_log));
            CHECK(log["summary"]["interrupted_by_signal"] == SIGTERM);
            int logged = 0;
            for (const auto& f : log["frames"]) {
                CHECK(f["status"] == "developed");
                CHECK(fs::exists(f["output"].get<std::string>()));
                ++logged;
            }
            CHECK(logged == done);
        }

        // The re-run keeps the finished frames, makes the rest and cleans what the kill left.
        Result r = darkroom("develop " + in + " -o " + out + look + " --no-clobber --log " + (dir / "log.json").string());
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        CHECK(temp_files_in(dir) == 0);
        nlohmann::json log = nlohmann::json::parse(file_bytes(dir / "log.json"));
        int skipped = 0;
        for (const auto& f : log["frames"]) skipped += f["status"] == "skipped (exists)";
        CHECK(skipped == done);
        for (int f = 1; f <= frames; ++f) CHECK(fs::exists(frame_name(dir, "out", f)));
    }
    // The resumed sequence is the sequence an uninterrupted run makes.
    fs::path clean = fresh_dir("killed-clean");
    REQUIRE(darkroom("develop " + in + " -o " + (clean / "out.####.exr").string() + look + " --threads 2 -q --frames 1,8")
                .exit_code == 0);
    for (int f : {1, frames}) CHECK(pixels(frame_name(clean, "out", f)) == pixels(frame_name(dir, "out", f)));
}

TEST_CASE("a reference render that will take hours says so before it starts", "[cli][batch][quality]") {
    fs::path dir = fresh_dir("reference-warning");
    const std::string in = make_input("reference-thumbnail.exr", 32, 24);
    // 32 px across a whole Super 35 frame: 780 um pixels, tens of millions of grains each.
    const fs::path out = dir / "thumb.exr", err = dir / "stderr.txt";
    pid_t pid = fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
        std::string command = std::string(DARKROOM_EXE) + " develop " + in + " -o " + out.string() +
                              " --quality reference --threads 1 2> " + err.string();
        execl("/bin/sh", "sh", "-c", ("exec " + command).c_str(), (char*)nullptr);
        _exit(127);
    }
    // The warning comes before the render: wait for it (a minute at most), then stop the run.
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    int status = 0;
    bool exited = false;
    while (file_bytes(err).find("warning") == std::string::npos && !exited &&
           std::chrono::steady_clock::now() < give_up) {
        exited = waitpid(pid, &status, WNOHANG) == pid;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    CHECK_FALSE(exited);  // still rendering: the warning came first
    if (!exited) {
        kill(pid, SIGTERM);
        waitpid(pid, &status, 0);
    }
    const std::string text = file_bytes(err);
    INFO(text);
    CHECK(text.find("--quality reference draws every silver grain") != std::string::npos);
    CHECK(text.find("CPU hours") != std::string::npos);
    CHECK_FALSE(fs::exists(out));
    // At a 4K frame's pitch (6 um on the film, 5.5 on the print) the same image is a quick
    // render and no warning.
    Result quick = darkroom("develop " + in + " -o " + (dir / "quick.exr").string() +
                            " --quality reference --frame-width-mm 0.195 --print-width-mm 0.175");
    INFO(quick.output);
    REQUIRE(quick.exit_code == 0);
    CHECK(quick.output.find("warning") == std::string::npos);
}

TEST_CASE("a reference render over its budget is refused before it starts", "[cli][batch][quality]") {
    fs::path dir = fresh_dir("reference-budget");
    const std::string in = make_input("reference-budget.exr", 32, 24);
    // 32 px across a 150 mm frame: 30 times a Super 35 frame's silver grains, days of CPU.
    const fs::path out = dir / "refused.exr";
    Result r = darkroom("develop " + in + " -o " + out.string() +
                       " --quality reference --frame-width-mm 150 --print-width-mm 150 --threads 1");
    INFO(r.output);
    CHECK(r.exit_code != 0);
    CHECK(r.output.find("--quality reference") != std::string::npos);
    CHECK(r.output.find("window 0,0,32,24") != std::string::npos);
    CHECK(r.output.find("budget of 24 CPU hours") != std::string::npos);
    CHECK_FALSE(fs::exists(out));
}

// Alpha (OpenImageIO's convention: premultiplied) is not read as colour: the grey, divided by
// it, develops as the grey alone would, and is multiplied by it again. A grey plate with
// alpha and depth (Y, A, Z: three channels, which by their count alone would be RGB) is grey
// by its names: the same pixels as Y, A, its depth passed through.
TEST_CASE("grey and alpha input develops as grey and keeps its alpha, as RGBA", "[cli][batch][metadata]") {
    fs::path dir = fresh_dir("grey-alpha");
    auto alpha_at = [](int x, int y) { return float((x * 7 + y * 3) % 11) / 10.0f; };  // unrelated to the grey, 0 to 1
    auto grey_at = [](int x, int y) { return 0.02f * float(1 + x + y); };
    auto depth_at = [](int x, int y) { return 100.0f + float(x * 16 + y); };
    auto write_grey = [&](const std::string& path, const std::vector<std::string>& names) {
        const bool with_alpha = names.size() > 1;
        OIIO::ImageSpec spec(24, 16, int(names.size()), OIIO::TypeDesc::FLOAT);
        spec.channelnames = names;
        spec.alpha_channel = with_alpha ? 1 : -1;
        spec.z_channel = names.size() > 2 ? 2 : -1;
        OIIO::ImageBuf buf(spec);
        for (OIIO::ImageBuf::Iterator<float> p(buf); !p.done(); ++p) {
            const float a = alpha_at(p.x(), p.y());
            // The straight grey, premultiplied where there is alpha (where it is 0, a grey that
            // is not: undivided, then multiplied by 0).
            p[0] = with_alpha ? grey_at(p.x(), p.y()) * (a > 0 ? a : 1.0f) : grey_at(p.x(), p.y());
            if (with_alpha) p[1] = a;
            if (names.size() > 2) p[2] = depth_at(p.x(), p.y());
        }
        REQUIRE(buf.write(path));
    };
    const std::string ya = (dir / "ya.exr").string(), y = (dir / "y.exr").string(), yaz = (dir / "yaz.exr").string();
    write_grey(ya, {"Y", "A"});
    write_grey(y, {"Y"});
    write_grey(yaz, {"Y", "A", "Z"});
    const std::string out_ya = (dir / "out-ya.exr").string(), out_y = (dir / "out-y.exr").string(),
                      out_yaz = (dir / "out-yaz.exr").string();
    for (const auto& [in, out] : {std::make_pair(ya, out_ya), std::make_pair(y, out_y), std::make_pair(yaz, out_yaz)}) {
        Result r = darkroom("develop " + in + " -o " + out + kLook);
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
    }
    auto file = OIIO::ImageInput::open(out_ya);
    REQUIRE(file);
    CHECK(file->spec().channelnames == std::vector<std::string>{"R", "G", "B", "A"});
    CHECK(file->spec().alpha_channel == 3);
    const std::vector<float> rgba = pixels(out_ya), rgb = pixels(out_y), grey_alpha = pixels(ya);
    REQUIRE(rgba.size() == 24 * 16 * 4);
    REQUIRE(rgb.size() == 24 * 16 * 3);
    for (int i = 0; i < 24 * 16; ++i) {
        const float a = grey_alpha[i * 2 + 1];
        REQUIRE(rgba[i * 4 + 3] == a);
        // (c a) / a may differ from c in the last bit, and the film carries that through.
        for (int c = 0; c < 3; ++c) REQUIRE(rgba[i * 4 + c] == Approx(rgb[i * 3 + c] * a).epsilon(1e-5).margin(1e-7));
        if (a == 0) REQUIRE(rgba[i * 4] == 0.0f);
    }
    file = OIIO::ImageInput::open(out_yaz);
    REQUIRE(file);
    CHECK(file->spec().channelnames == std::vector<std::string>{"R", "G", "B", "A", "Z"});
    CHECK(file->spec().alpha_channel == 3);
    CHECK(file->spec().z_channel == 4);
    const std::vector<float> rgbaz = pixels(out_yaz);
    REQUIRE(rgbaz.size() == 24 * 16 * 5);
    for (int i = 0; i < 24 * 16; ++i) {
        for (int c = 0; c < 4; ++c) REQUIRE(rgbaz[i * 5 + c] == rgba[i * 4 + c]);
        REQUIRE(rgbaz[i * 5 + 4] == depth_at(i % 24, i / 24));
    }
}

// An alpha that is no coverage (negative, above 1, infinite, NaN) counts as its nearest one
// (NaN: 0): the colour stays finite, 0 where the coverage is 0, and the alpha passes through.
TEST_CASE("a bad alpha counts as its nearest coverage and leaves the colour finite", "[cli][batch][bad-input]") {
    fs::path dir = fresh_dir("bad-alpha");
    const float alphas[] = {-0.5f, 0.0f, 1.0f, 2.0f, INFINITY, -INFINITY, NAN};
    const int n = int(std::size(alphas));
    OIIO::ImageBuf buf(OIIO::ImageSpec(n, 4, 4, OIIO::TypeDesc::FLOAT));
    for (OIIO::ImageBuf::Iterator<float> p(buf); !p.done(); ++p) {
        for (int c = 0; c < 3; ++c) p[c] = 0.18f;
        p[3] = alphas[p.x()];
    }
    const std::string in = (dir / "in.exr").string(), out = (dir / "out.exr").string();
    REQUIRE(buf.write(in));
    Result r = darkroom("develop " + in + " -o " + out + kLook + " --no-grain");  // a flat picture, a flat print
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    const std::vector<float> px = pixels(out);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < n; ++x) {
            const float* p = &px[(size_t(y) * n + x) * 4];
            INFO("alpha " << alphas[x]);
            for (int c = 0; c < 3; ++c) CHECK(std::isfinite(p[c]));
            if (!(alphas[x] > 0)) CHECK(p[0] == 0.0f);
            CHECK((std::isnan(alphas[x]) ? std::isnan(p[3]) : p[3] == alphas[x]));
        }
    // Beyond 1 counts as 1: the same colour as an opaque pixel's.
    CHECK(px[3 * 4] == px[2 * 4]);
    CHECK(px[4 * 4] == px[2 * 4]);
}

// An EXR of the pattern below on the data window (x, y, width, height) of a 128x96 display window.
static void write_part_of_frame(const std::string& path, int x, int y, int width, int height) {
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::FLOAT);
    spec.x = x;
    spec.y = y;
    spec.full_x = spec.full_y = 0;
    spec.full_width = 128;
    spec.full_height = 96;
    OIIO::ImageBuf buf(spec);
    for (OIIO::ImageBuf::Iterator<float> p(buf); !p.done(); ++p)
        for (int c = 0; c < 3; ++c)
            p[c] = float(0.02 + 0.5 * (1.0 + std::sin(0.21 * p.x() + 0.13 * p.y() + c)) * (1.0 + (p.x() / 9 + p.y() / 7) % 3));
    REQUIRE(buf.write(path));
}

TEST_CASE("a file holding part of the frame (a CG element's bounding box, overscan) develops as that part of the frame",
          "[cli][batch][metadata]") {
    // The film frame is the display window: the pixel pitch and the grain follow it, so the
    // pixels away from the data window's edges (where filters clamp) are the whole frame's.
    fs::path dir = fresh_dir("data-window");
    const std::string look = kLook + " --halation 0 --threads 2";
    struct Part {
        const char* name;
        int x, y, width, height;
        int compare_x0, compare_y0, compare_x1, compare_y1;  // display pixels 12 or more from every edge
    };
    const Part whole{"whole", 0, 0, 128, 96, 0, 0, 0, 0};
    const Part parts[] = {{"bounding-box", 32, 24, 64, 48, 44, 36, 84, 60}, {"overscan", -10, -8, 148, 112, 12, 12, 116, 84}};
    write_part_of_frame((dir / "whole.exr").string(), whole.x, whole.y, whole.width, whole.height);
    REQUIRE(darkroom("develop " + (dir / "whole.exr").string() + " -o " + (dir / "whole-out.exr").string() + look).exit_code == 0);
    const std::vector<float> frame = pixels((dir / "whole-out.exr").string());
    for (const Part& part : parts) {
        INFO(part.name);
        const std::string in = (dir / (std::string(part.name) + ".exr")).string(),
                          out = (dir / (std::string(part.name) + "-out.exr")).string();
        write_part_of_frame(in, part.x, part.y, part.width, part.height);
        Result r = darkroom("develop " + in + " -o " + out + look + " -v");
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        CHECK(r.output.find("pixel pitch 23.44 um") != std::string::npos);  // 3 mm over the display's 128 px
        OIIO::ImageSpec spec;
        const std::vector<float> got = pixels(out, &spec);
        CHECK(spec.x == part.x);
        CHECK(spec.y == part.y);
        CHECK(spec.width == part.width);
        for (int y = part.compare_y0; y < part.compare_y1; ++y)
            for (int x = part.compare_x0; x < part.compare_x1; ++x)
                for (int c = 0; c < 3; ++c)
                    REQUIRE(got[((y - part.y) * part.width + (x - part.x)) * 3 + c] == frame[(y * 128 + x) * 3 + c]);
    }
}

// A layer's channels keep their names: developing a render's "diffuse" layer alone gives a
// "diffuse" layer, and the beauty's further layers pass through under their own names. A grey
// input's colour becomes R, G, B and its depth stays depth (not alpha).
TEST_CASE("the output's channels keep the input's names", "[cli][batch][metadata]") {
    fs::path dir = fresh_dir("channel-names");
    using Names = std::vector<std::string>;
    struct Case {
        Names in, out;
        int out_alpha, out_z;
    };
    for (const Case& c : {Case{{"diffuse.R", "diffuse.G", "diffuse.B"}, {"diffuse.R", "diffuse.G", "diffuse.B"}, -1, -1},
                          Case{{"R", "G", "B", "A", "diffuse.R", "diffuse.G", "diffuse.B"},
                               {"R", "G", "B", "A", "diffuse.R", "diffuse.G", "diffuse.B"}, 3, -1},
                          Case{{"Y", "Z"}, {"R", "G", "B", "Z"}, -1, 3},
                          Case{{"Y", "A"}, {"R", "G", "B", "A"}, 3, -1},
                          Case{{"Y", "A", "Z"}, {"R", "G", "B", "A", "Z"}, 3, 4}}) {
        const Names& names = c.in;
        OIIO::ImageSpec spec(12, 8, int(names.size()), OIIO::TypeDesc::FLOAT);
        spec.channelnames = names;
        spec.alpha_channel = int(std::find(names.begin(), names.end(), "A") - names.begin());
        if (spec.alpha_channel == int(names.size())) spec.alpha_channel = -1;
        spec.z_channel = int(std::find(names.begin(), names.end(), "Z") - names.begin());
        if (spec.z_channel == int(names.size())) spec.z_channel = -1;
        OIIO::ImageBuf buf(spec);
        std::vector<float> value(names.size(), 0.18f);
        OIIO::ImageBufAlgo::fill(buf, value);
        const std::string in = (dir / "layers.exr").string(), out = (dir / "out.exr").string();
        REQUIRE(buf.write(in));
        Result r = darkroom("develop " + in + " -o " + out + kLook);
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        auto file = OIIO::ImageInput::open(out);
        REQUIRE(file);
        CHECK(file->spec().channelnames == c.out);
        CHECK(file->spec().alpha_channel == c.out_alpha);
        CHECK(file->spec().z_channel == c.out_z);
    }
}

TEST_CASE("metadata, windows, pixel aspect and extra channels survive", "[cli][batch][metadata]") {
    fs::path dir = fresh_dir("metadata");
    std::string in = (dir / "plate.exr").string(), out = (dir / "out.exr").string();
    OIIO::ImageSpec spec(40, 30, 5, OIIO::TypeDesc::FLOAT);
    spec.x = 7;
    spec.y = 5;
    spec.full_x = 0;
    spec.full_y = 0;
    spec.full_width = 64;
    spec.full_height = 48;
    spec.channelnames = {"R", "G", "B", "A", "Z"};
    spec.alpha_channel = 3;
    spec.z_channel = 4;
    spec.attribute("PixelAspectRatio", 2.0f);
    spec.attribute("shot", "sh010");
    spec.attribute("Exif:ImageHistory", "oiiotool plate.dpx -o plate.exr");
    OIIO::ImageBuf buf(spec);
    for (OIIO::ImageBuf::Iterator<float> p(buf); !p.done(); ++p)
        for (int c = 0; c < 5; ++c) p[c] = 0.1f * (c + 1) + 0.001f * p.x();
    REQUIRE(buf.write(in));

    Result r = darkroom("develop " + in + " -o " + out + kLook + " -d half --compression piz");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    std::vector<float> px = pixels(out);
    auto file = OIIO::ImageInput::open(out);
    REQUIRE(file);
    const OIIO::ImageSpec got = file->spec();
    CHECK(got.x == 7);
    CHECK(got.y == 5);
    CHECK(got.full_width == 64);
    CHECK(got.full_height == 48);
    CHECK(got.format == OIIO::TypeDesc::HALF);
    CHECK(got.get_string_attribute("compression") == "piz");
    CHECK(got.get_float_attribute("PixelAspectRatio") == 2.0f);
    CHECK(got.get_string_attribute("shot") == "sh010");
    CHECK(got.channelnames == std::vector<std::string>{"R", "G", "B", "A", "Z"});
    CHECK(got.alpha_channel == 3);
    CHECK(got.z_channel == 4);
    for (int i = 0; i < 40 * 30; ++i) {
        REQUIRE(px[i * 5 + 3] == Approx(0.4f + 0.001f * (7 + i % 40)).epsilon(1e-3));  // half precision
        REQUIRE(px[i * 5 + 4] == Approx(0.5f + 0.001f * (7 + i % 40)).epsilon(1e-3));
    }
    const std::string history = got.get_string_attribute("Exif:ImageHistory");
    CHECK_THAT(history, Catch::StartsWith("oiiotool plate.dpx -o plate.exr\ndarkroom develop"));
    CHECK_THAT(got.get_string_attribute("Software"), Catch::StartsWith("darkroom ") && Catch::Contains("--seed 11"));
    nlohmann::json look = nlohmann::json::parse(got.get_string_attribute("darkroom:look"));
    CHECK(look["format"] == "darkroom-look");
    CHECK(look["settings"]["seed"] == 11);
    CHECK(look["settings"]["frame-width-mm"] == 3);
}

TEST_CASE("a look file round-trips and flags override it", "[cli][batch][look]") {
    fs::path dir = fresh_dir("look");
    std::string in = make_input("look-in.exr", 40, 30), look = (dir / "look.json").string(),
                again = (dir / "again.json").string();
    const std::string settings = kLook + " --exposure 0.5 --output negative --no-mtf";
    REQUIRE(darkroom("develop --save-look " + look + settings).exit_code == 0);
    nlohmann::json saved = nlohmann::json::parse(file_bytes(look));
    CHECK(saved["version"] == 1);
    CHECK(saved["settings"]["exposure"] == 0.5);
    CHECK(saved["settings"]["output"] == "negative");
    CHECK(saved["settings"]["mtf"] == false);
    CHECK(saved["settings"]["grain"] == true);
    for (const char* run_option : {"threads", "frame", "out", "look", "verbose"})
        CHECK_FALSE(saved["settings"].contains(run_option));

    // Loading and saving again gives the same file; developing with it gives the same pixels.
    REQUIRE(darkroom("develop --look " + look + " --save-look " + again).exit_code == 0);
    CHECK(nlohmann::json::parse(file_bytes(again)) == saved);
    std::string by_flags = (dir / "flags.exr").string(), by_look = (dir / "look.exr").string(),
                overridden = (dir / "override.exr").string(), by_flags2 = (dir / "flags2.exr").string();
    REQUIRE(darkroom("develop " + in + " -o " + by_flags + settings).exit_code == 0);
    REQUIRE(darkroom("develop " + in + " -o " + by_look + " --look " + look).exit_code == 0);
    CHECK(pixels(by_look) == pixels(by_flags));

    // A flag on the command line wins over the file.
    REQUIRE(darkroom("develop " + in + " -o " + overridden + " --look " + look + " --exposure -1").exit_code == 0);
    REQUIRE(darkroom("develop " + in + " -o " + by_flags2 + kLook + " --exposure -1 --output negative --no-mtf")
                .exit_code == 0);
    CHECK(pixels(overridden) == pixels(by_flags2));
    CHECK(pixels(overridden) != pixels(by_flags));
}

TEST_CASE("a bad look file is named with its problem", "[cli][batch][look][bad-input]") {
    fs::path dir = fresh_dir("bad-look");
    std::string in = make_input("bad-look-in.exr", 16, 12), out = (dir / "never.exr").string();
    struct Case {
        std::string json, message;
    };
    for (const Case& c : std::vector<Case>{
             {R"({"format": "darkroom-look", "version": 1, "settings": {"exposur": 1}})", "setting 'exposur': unknown"},
             {R"({"format": "darkroom-look", "version": 2, "settings": {}})", "'version'"},
             {R"({"format": "darkroom-stock", "version": 1})", "not a darkroom look"},
             {R"({"format": "darkroom-look", "version": 1, "settings": {"threads": 4}})", "run option"},
             {R"({"format": "darkroom-look", "version": 1, "settings": {"exposure": "lots"}})", "setting 'exposure'"},
             {R"({"format": "darkroom-look", "version": 1, "settings": {"output": "slide"}})", "setting 'output'"},
             {R"({"format": "darkroom-look", "version": 1, "setings": {}})", "unknown field 'setings'"},
             {R"({"format": "darkroom-look", )", "not valid JSON"},
         }) {
        std::string look = (dir / "look.json").string();
        std::ofstream(look) << c.json;
        Result r = darkroom("develop " + in + " -o " + out + " --look " + look);
        INFO(c.json << "\n" << r.output);
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.output, Catch::Contains(c.message) && Catch::Contains("look.json"));
    }
    CHECK_FALSE(fs::exists(out));
}

TEST_CASE("dry run and no-clobber write nothing and an input is replaced only when named as the output", "[cli][batch][safe-writes]") {
    fs::path dir = fresh_dir("dry-run");
    make_plates(dir, 1, 2, 16, 12);
    const std::string seq_in = (dir / "plate.####.exr").string();
    Result r = darkroom("develop " + seq_in + " -o " + (dir / "out.####.exr").string() + " -n");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.output, Catch::Contains("plate.0002.exr -> ") && Catch::Contains("dry run"));
    CHECK_FALSE(fs::exists(frame_name(dir, "out", 1)));
    // A frame the run could not read is named by the dry run, from its header.
    std::ofstream(frame_name(dir, "plate", 3)) << "not an image";
    r = darkroom("develop " + seq_in + " -o " + (dir / "out.####.exr").string() + " --frames 1-4 -n");
    INFO(r.output);
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.output, Catch::Contains("cannot read '" + frame_name(dir, "plate", 3) + "'") &&
                             Catch::Contains("input '" + frame_name(dir, "plate", 4) + "' does not exist"));
    fs::remove(frame_name(dir, "plate", 3));

    // An output that only resolves to an input is refused; naming the input itself replaces it.
    const std::string before = file_bytes(frame_name(dir, "plate", 1));
    r = darkroom("develop " + frame_name(dir, "plate", 1) + " -o " + (dir / "plate.#.exr").string() +
                 " --frames 1-2 --skip-bad-frames --no-grain --no-mtf");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("refusing to overwrite the input"));
    CHECK(file_bytes(frame_name(dir, "plate", 1)) == before);
    fs::create_symlink(frame_name(dir, "plate", 1), dir / "link.exr");
    r = darkroom("develop " + frame_name(dir, "plate", 1) + " -o " + (dir / "link.exr").string());
    CHECK_THAT(r.output, Catch::Contains("refusing to overwrite the input"));
    CHECK(file_bytes(frame_name(dir, "plate", 1)) == before);

    const std::vector<float> plate = pixels(frame_name(dir, "plate", 1));
    r = darkroom("develop " + seq_in + " -o " + seq_in + " --no-grain --no-mtf");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK(pixels(frame_name(dir, "plate", 1)) != plate);
    CHECK(temp_files_in(dir) == 0);

    // --no-clobber leaves an existing output alone.
    std::string out = (dir / "single.exr").string();
    std::ofstream(out) << "not touched";
    REQUIRE(darkroom("develop " + frame_name(dir, "plate", 1) + " -o " + out + " --no-clobber").exit_code == 0);
    CHECK(file_bytes(out) == "not touched");
}

TEST_CASE("threads come from --threads, else OPENIMAGEIO_THREADS, and never change the pixels", "[cli][batch][determinism]") {
    fs::path dir = fresh_dir("threads");
    make_plates(dir, 1, 3, 24, 16);
    const std::string seq = "develop " + (dir / "plate.#.exr").string() + " -o ";
    Result r = shell("OPENIMAGEIO_THREADS=3 " + std::string(DARKROOM_EXE) + " " + seq + (dir / "a.#.exr").string() +
                     kLook + " -v");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.output, Catch::Contains("threads: 3 (3 frames at once, 1 per frame)"));
    r = shell("OPENIMAGEIO_THREADS=3 " + std::string(DARKROOM_EXE) + " " + seq + (dir / "b.#.exr").string() + kLook +
              " -v --threads 2 --frames-at-once 1");
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.output, Catch::Contains("threads: 2 (1 frame at once, 2 per frame)"));
    for (int f = 1; f <= 3; ++f) CHECK(pixels(frame_name(dir, "a", f)) == pixels(frame_name(dir, "b", f)));
}

TEST_CASE("progress: a bar on a terminal, a line per frame otherwise", "[cli][batch][progress]") {
    fs::path dir = fresh_dir("progress");
    make_plates(dir, 1, 2, 16, 12);
    const std::string args = " develop " + (dir / "plate.#.exr").string() + " -o " + (dir / "out.#.exr").string() +
                             " --no-grain --no-mtf";
    Result lines = darkroom(args);
    REQUIRE(lines.exit_code == 0);
    CHECK_THAT(lines.output, Catch::Contains("frame 2: ") && Catch::Contains("developed in"));
    CHECK_THAT(lines.output, !Catch::Contains("fps"));
    // script(1) gives the program a terminal.
    Result bar = shell("script -qec '" + std::string(DARKROOM_EXE) + args + " --no-clobber' /dev/null");
    INFO(bar.output);
    REQUIRE(bar.exit_code == 0);
    CHECK_THAT(bar.output, Catch::Contains("2/2 frames") && Catch::Contains("fps") && Catch::Contains("left"));
    CHECK_THAT(bar.output, !Catch::Contains("frame 2: "));
    CHECK(bar.output.substr(bar.output.rfind("left")) == "left\r\n");  // (a terminal's newline)
}

TEST_CASE("an interrupted run ends the bar's line before it says so", "[cli][batch][progress][safe-writes]") {
    fs::path dir = fresh_dir("progress-interrupted");
    make_plates(dir, 1, 6, 160, 120);
    const std::string first_output = frame_name(dir, "out", 1);
    // Killed once its first frame is written, while the bar is on the terminal script(1) gives it.
    const std::string run = std::string(DARKROOM_EXE) + " develop " + (dir / "plate.#.exr").string() + " -o " +
                            (dir / "out.#.exr").string() + kLook + " --threads 1 --frames-at-once 1 & " +
                            "while [ ! -e " + first_output + " ]; do sleep 0.02; done; kill -TERM $!; wait $!";
    Result r = shell("script -qec '" + run + "' /dev/null");
    INFO(r.output);
    const size_t interrupted = r.output.find("darkroom: interrupted by signal 15");
    REQUIRE(interrupted != std::string::npos);
    CHECK_THAT(r.output.substr(0, interrupted), Catch::Contains("frames") && Catch::EndsWith("left\r\n"));
}

TEST_CASE("a sequence that cannot be made is refused before any work", "[cli][batch][bad-input]") {
    fs::path dir = fresh_dir("bad-sequence");
    make_plates(dir, 1, 2, 8, 6);
    const std::string seq = (dir / "plate.####.exr").string(), out = (dir / "out.####.exr").string();
    struct Case {
        std::string args, message;
    };
    for (const Case& c : std::vector<Case>{
             {seq + " -o " + (dir / "single.exr").string(), "needs a frame number wildcard"},
             {seq + " -o " + out + " --frames abc", "--frames 'abc' is not a frame range"},
             {(dir / "nothere.####.exr").string() + " -o " + out, "no files match the input sequence"},
             {seq + " -o " + out + " --frame 3", "--frame is for a single image"},
             {frame_name(dir, "plate", 1) + " -o " + out, "name the frames with --frames"},
             {frame_name(dir, "plate", 1) + " -o " + (dir / "x.exr").string() + " --frames 1-3", "--frames needs"},
         }) {
        Result r = darkroom("develop " + c.args);
        INFO(c.args << "\n" << r.output);
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.output, Catch::Contains(c.message));
    }
    CHECK_FALSE(fs::exists(frame_name(dir, "out", 1)));
}

// A plate's grain profile is read once a run, before any frame: a bad one is the run's error
// (no frame started), and its warning of another colour space is said once, not per frame.
TEST_CASE("a grain profile is read once a run, before any frame", "[cli][batch][grain][bad-input]") {
    fs::path dir = fresh_dir("profile-once");
    make_plates(dir, 1, 3, 16, 12);
    const std::string seq = (dir / "plate.####.exr").string(), out = (dir / "out.####.exr").string();
    const std::string corrupt = (dir / "corrupt.json").string();
    std::ofstream(corrupt) << "{\"format\": \"darkroom-grain-profile\", \"version\": 1, \"channels\": []}";
    Result r = darkroom("develop " + seq + " -o " + out + kLook + " --grain-profile " + corrupt);
    INFO(r.output);
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains(corrupt));
    CHECK(r.output.find("frame 1") == std::string::npos);
    CHECK_FALSE(fs::exists(frame_name(dir, "out", 1)));

    nlohmann::json profile;
    {
        const std::string predicted = (dir / "predicted.json").string();
        REQUIRE(darkroom("grain predict --stock kodak-vision3-500t --width 2048 -o " + predicted).exit_code == 0);
        std::ifstream f(predicted);
        profile = nlohmann::json::parse(f);
    }
    profile["colorspace"] = "Cineon Log";
    profile["encoding"] = "linear";  // as develop's output, so that only the names differ
    const std::string measured = (dir / "measured-in-cineon.json").string();
    std::ofstream(measured) << profile.dump();
    r = darkroom("develop " + seq + " -o " + out + kLook + " --grain-profile " + measured + " --tocolorspace ACEScg -q");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK(count(r.output, "the grain profile was measured in 'Cineon Log' but the output is in 'ACEScg'") == 1);
    CHECK(fs::exists(frame_name(dir, "out", 3)));
    // The demo has no plate to match: refused, not left without grain.
    r = darkroom("demo -o " + (dir / "demo").string() + " --grain-profile " + measured);
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("--grain-profile applies to develop"));
}

// A single image's warnings and failure name no frame (the wording is a sequence's) and are
// printed once each; a sequence's name their frame. Every warning is in the log either way.
TEST_CASE("a single image's messages name no frame and come once, a sequence's name the frame", "[cli][batch][bad-input]") {
    fs::path dir = fresh_dir("messages");
    const std::string nan_image = grey_plate_with_nan(dir), corrupt = (dir / "corrupt.exr").string();
    std::ofstream(corrupt) << "this is not an EXR file";

    Result r = darkroom("develop " + nan_image + " -o " + (dir / "out.exr").string() + " --log " +
                        (dir / "log.json").string());
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK(count(r.output, "darkroom: warning: 1 non-finite colour values") == 1);
    CHECK(count(r.output, "non-finite") == 1);
    CHECK(r.output.find("frame 0") == std::string::npos);
    const nlohmann::json log = nlohmann::json::parse(file_bytes(dir / "log.json"));
    CHECK(log["frames"][0]["warnings"].size() == 1);

    r = darkroom("develop " + corrupt + " -o " + (dir / "out2.exr").string());
    INFO(r.output);
    CHECK(r.exit_code == 1);
    CHECK(count(r.output, "is not an OpenEXR file") == 1);
    CHECK(r.output.find("frame 0") == std::string::npos);

    fs::copy_file(nan_image, dir / "plate.0001.exr");
    fs::copy_file(corrupt, dir / "plate.0002.exr");
    r = darkroom("develop " + (dir / "plate.####.exr").string() + " -o " + (dir / "o.####.exr").string() +
                 " --skip-bad-frames --frames-at-once 1");
    INFO(r.output);
    CHECK(r.exit_code == 1);
    CHECK(count(r.output, "darkroom: frame 1: warning: 1 non-finite colour values") == 1);
    CHECK(count(r.output, "darkroom: frame 2 (" + (dir / "plate.0002.exr").string() + ") failed") == 1);
}

// Only what film reads is counted: the colour, and the alpha it is premultiplied by. A depth
// of +Inf (a render's background) passes through and says nothing.
TEST_CASE("non-finite values are counted in the colour and the alpha, not in the channels passed through",
          "[cli][batch][bad-input]") {
    fs::path dir = fresh_dir("non-finite-channels");
    OIIO::ImageSpec spec(8, 6, 5, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {"R", "G", "B", "A", "Z"};
    spec.alpha_channel = 3;
    spec.z_channel = 4;
    OIIO::ImageBuf render(spec);
    const float background[5] = {0.1f, 0.1f, 0.1f, 1.0f, INFINITY};
    OIIO::ImageBufAlgo::fill(render, background);
    const std::string clean = (dir / "depth.exr").string(), bad_alpha = (dir / "bad-alpha.exr").string();
    REQUIRE(render.write(clean));
    const float nan_alpha[5] = {0.1f, -INFINITY, 0.1f, NAN, INFINITY};
    render.setpixel(1, 2, nan_alpha);
    render.setpixel(2, 2, nan_alpha);
    REQUIRE(render.write(bad_alpha));

    Result r = darkroom("develop " + clean + " -o " + (dir / "a.exr").string());
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK(r.output.find("warning") == std::string::npos);
    r = darkroom("develop " + bad_alpha + " -o " + (dir / "b.exr").string());
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK(r.output.find("2 non-finite colour values") != std::string::npos);
    CHECK(r.output.find("2 non-finite alpha values") != std::string::npos);
    // The colour is finite; the alpha and the depth pass through as they were.
    const std::vector<float> in = pixels(bad_alpha), out = pixels((dir / "b.exr").string());
    REQUIRE(out.size() == in.size());
    for (size_t i = 0; i < out.size(); ++i) {
        if (i % 5 < 3) CHECK(std::isfinite(out[i]));
        else CHECK((out[i] == in[i] || (std::isnan(out[i]) && std::isnan(in[i]))));
    }
}

// With --window, only the pixels the render reads are counted: the window and its halo (here
// none: no MTF, no halation), not a bad pixel elsewhere in the file that cannot reach it.
TEST_CASE("non-finite values are counted where a window's render reads them", "[cli][batch][bad-input]") {
    fs::path dir = fresh_dir("non-finite-window");
    const std::string in = grey_plate_with_nan(dir);
    const std::string flags = " --no-mtf --halation 0 --no-grain --window ";
    Result r = darkroom("develop " + in + " -o " + (dir / "away.exr").string() + flags + "8,0,8,12");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK(r.output.find("non-finite") == std::string::npos);
    r = darkroom("develop " + in + " -o " + (dir / "over.exr").string() + flags + "3,4,2,2");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK(r.output.find("1 non-finite colour values") != std::string::npos);
}
