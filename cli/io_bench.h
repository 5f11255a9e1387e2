// darkroom bench --io: the program as a render farm runs it, timed from outside, program
// start included, on plates made of the demo scene with a camera's noise. An HD half-float
// ZIP sequence is developed three ways (one frame after another; frames at once without
// overlap; frames at once, each written while the next is read and developed) and a 4K
// float ZIP frame is developed against oiiotool copying it, in pairs, when oiiotool is on
// PATH.
#pragma once

#include <nlohmann/json.hpp>

namespace darkroom::cli {

struct IoBenchOptions {
    int sequence_width = 1920, sequence_height = 1080, sequence_frames = 6;
    int frame_width = 4096, frame_height = 2160;
    int rounds = 3;    // of each timing; the median is kept
    int threads = 0;   // 0 = all cores
};

// The measurements as JSON (machine-readable, and what the table is printed from).
nlohmann::json run_io_bench(const IoBenchOptions& options);

void print_io_bench(const nlohmann::json& report);

}  // namespace darkroom::cli
