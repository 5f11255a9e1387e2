// Frame sequences in oiiotool's syntax, through OpenImageIO's own parser:
//   plate.#.exr       '#' alone: the frame number padded to 4 digits (or --framepadding)
//   plate.####.exr    a run of '#': one digit per '#' (the Nuke convention: 4 digits here;
//                     oiiotool would read 4 digits per '#', i.e. 16)
//   plate.@@@.exr     one digit per '@'
//   plate.%04d.exr    printf style
//   plate.1-100#.exr  a frame range in the name itself
// Frame ranges (--frames): "1-100", "1-100x2" (every 2nd), "1-100y2" (the complement of
// x2), "10-1" (backwards), comma-separated lists of these.
#pragma once

#include <string>
#include <vector>

namespace darkroom::cli {

// The most frames one run takes (11.5 hours at 24 fps): each costs a few hundred bytes
// before any work, so a mistyped range would fill the memory.
inline constexpr int kMaxFrames = 1000000;

struct FrameJob {
    int frame = 0;
    std::string input, output;
};

struct SequenceOptions {
    std::string frames;    // --frames; empty: the range in the name, else the files on disk
    int framepadding = 0;  // --framepadding; 0: as the pattern says
};

struct ExpandedFrames {
    std::vector<FrameJob> jobs;
    // For an input sequence found on disk, the frames absent between its first and last,
    // as ranges ("6, 9-11"); empty when none are or the frames were named.
    std::string missing_frames;
};

// Whether `path` names a sequence (holds a frame number wildcard).
bool is_sequence_pattern(const std::string& path);

// Expands the input and output names into one job per frame. Without a wildcard in either
// name there is one job, for `single_frame`. An input sequence needs an output sequence; a
// single input with an output sequence develops the same image at each frame (moving grain
// on a still). Throws UserError for a bad range, a wildcard missing where one is needed, or
// a sequence with no frames.
ExpandedFrames expand_frames(const std::string& input, const std::string& output, const SequenceOptions& sequence,
                             int single_frame);

}  // namespace darkroom::cli
