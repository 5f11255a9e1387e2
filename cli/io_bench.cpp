#include "cli/io_bench.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <random>
#include <thread>
#include <unistd.h>

#include "cli/batch.h"
#include "cli/image_io.h"
#include "core/demo_scene.h"

namespace darkroom::cli {

namespace {

namespace fs = std::filesystem;

// A folder of its own for the bench's files, removed with them.
struct ScratchFolder {
    fs::path path = fs::temp_directory_path() / ("darkroom-bench-io-" + std::to_string(getpid()));
    ScratchFolder() { fs::create_directories(path); }
    ~ScratchFolder() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
};

std::string quoted(const std::string& text) { return "'" + text + "'"; }

// Wall-clock seconds `command` takes, its output discarded; UserError if it fails.
double timed_run(const std::string& command) {
    const auto start = std::chrono::steady_clock::now();
    if (std::system((command + " > /dev/null 2>&1").c_str()) != 0)
        throw UserError("bench --io: '" + command + "' failed");
    return seconds_since(start);
}

double median(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    const size_t n = values.size();
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

bool on_path(const std::string& program) {
    return std::system(("command -v " + program + " > /dev/null 2>&1").c_str()) == 0;
}

// The demo scene at this size with a camera plate's noise (3 % of each value: a smooth
// picture would compress far faster than a plate or a developed frame with its grain),
// written as an OpenEXR of `data_type` with ZIP compression.
void write_plate(const fs::path& path, int width, int height, const std::string& data_type) {
    Image plate = demo_scene(width, height);
    std::mt19937 random(1);
    std::uniform_real_distribution<float> noise(-0.03f, 0.03f);
    for (float& v : plate.pixels) v *= 1 + noise(random);
    WriteOptions write;
    write.data_type = data_type;
    write.compression = "zip";
    write_image(path.string(), plate, OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::FLOAT), "", write);
}

}  // namespace

nlohmann::json run_io_bench(const IoBenchOptions& o) {
    const ScratchFolder scratch;
    const std::string self = fs::read_symlink("/proc/self/exe").string();
    const std::string threads = " --threads " + std::to_string(o.threads);
    nlohmann::json report;
    report["rounds"] = o.rounds;
    report["threads"] = o.threads > 0 ? o.threads : int(std::max(1u, std::thread::hardware_concurrency()));

    // The sequence: each way in turn, round after round, so that the machine's drift falls on all.
    std::cerr << "bench: writing " << o.sequence_frames << " frames of " << o.sequence_width << "x" << o.sequence_height
              << " half-float ZIP\n";
    for (int f = 1; f <= o.sequence_frames; ++f) {
        char name[32];
        std::snprintf(name, sizeof name, "plate.%04d.exr", f);
        write_plate(scratch.path / name, o.sequence_width, o.sequence_height, "half");
    }
    const std::string sequence = quoted((scratch.path / "plate.####.exr").string());
    const std::string outputs = quoted((scratch.path / "out.####.exr").string());
    struct Way {
        const char* name;
        std::string flags;
        std::vector<double> seconds;
    };
    std::vector<Way> ways{{"one frame after another", " --frames-at-once 1 --no-overlap", {}},
                          {"frames at once, no overlap", " --no-overlap", {}},
                          {"frames at once, overlapped", "", {}}};
    for (int round = 0; round < o.rounds; ++round)
        for (Way& way : ways) {
            std::cerr << "bench: sequence, " << way.name << " (round " << round + 1 << " of " << o.rounds << ")\n";
            way.seconds.push_back(timed_run(quoted(self) + " develop " + sequence + " -o " + outputs + " -q" + threads +
                                            way.flags));
        }
    nlohmann::json seq = {{"width", o.sequence_width},
                          {"height", o.sequence_height},
                          {"frames", o.sequence_frames},
                          {"input", "half float, ZIP, the demo scene with 3 % noise"},
                          {"ways", nlohmann::json::array()}};
    for (const Way& way : ways) {
        const double seconds = median(way.seconds);
        seq["ways"].push_back({{"way", way.name},
                               {"flags", way.flags},
                               {"median_seconds", seconds},
                               {"frames_per_second", o.sequence_frames / seconds}});
    }
    report["sequence"] = seq;

    // The whole process on one frame against oiiotool's copy, in pairs.
    nlohmann::json whole = {{"width", o.frame_width}, {"height", o.frame_height}, {"input", "float, ZIP, the demo scene with 3 % noise"}};
    whole["oiiotool_on_path"] = on_path("oiiotool");
    if (whole["oiiotool_on_path"]) {
        std::cerr << "bench: writing a " << o.frame_width << "x" << o.frame_height << " float ZIP frame\n";
        const std::string frame = (scratch.path / "frame.exr").string();
        write_plate(frame, o.frame_width, o.frame_height, "float");
        std::vector<double> developed, copied, ratios;
        for (int round = 0; round < o.rounds; ++round) {
            std::cerr << "bench: whole process against oiiotool (pair " << round + 1 << " of " << o.rounds << ")\n";
            developed.push_back(timed_run(quoted(self) + " develop " + quoted(frame) + " -o " +
                                          quoted((scratch.path / "developed.exr").string()) + threads));
            copied.push_back(timed_run("oiiotool" + threads + " " + quoted(frame) + " -o " +
                                       quoted((scratch.path / "copied.exr").string())));
            ratios.push_back(developed.back() / copied.back());
        }
        whole["develop_median_seconds"] = median(developed);
        whole["oiiotool_median_seconds"] = median(copied);
        whole["ratio_median_of_pairs"] = median(ratios);
    }
    report["whole_process"] = whole;
    return report;
}

void print_io_bench(const nlohmann::json& r) {
    const nlohmann::json& seq = r["sequence"];
    std::printf("darkroom bench --io: the program timed from outside, program start included; median of %d rounds, "
                "%d threads\n\n",
                r["rounds"].get<int>(), r["threads"].get<int>());
    std::printf("sequence: %d frames of %dx%d %s\n", seq["frames"].get<int>(), seq["width"].get<int>(),
                seq["height"].get<int>(), seq["input"].get<std::string>().c_str());
    const double first_fps = seq["ways"][0]["frames_per_second"];
    for (const auto& way : seq["ways"])
        std::printf("  %-30s %8.2f s %8.3f fps  %.2fx\n", way["way"].get<std::string>().c_str(),
                    way["median_seconds"].get<double>(), way["frames_per_second"].get<double>(),
                    way["frames_per_second"].get<double>() / first_fps);
    const nlohmann::json& whole = r["whole_process"];
    std::printf("\nwhole process: develop a %dx%d %s frame against 'oiiotool in.exr -o out.exr'\n",
                whole["width"].get<int>(), whole["height"].get<int>(), whole["input"].get<std::string>().c_str());
    if (!whole["oiiotool_on_path"]) {
        std::printf("  not measured: oiiotool is not on PATH\n");
        return;
    }
    std::printf("  darkroom develop %8.2f s\n  oiiotool         %8.2f s\n  ratio            %8.2fx (median of %d pairs)\n",
                whole["develop_median_seconds"].get<double>(), whole["oiiotool_median_seconds"].get<double>(),
                whole["ratio_median_of_pairs"].get<double>(), r["rounds"].get<int>());
}

}  // namespace darkroom::cli
