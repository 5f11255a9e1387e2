#include "cli/sequence.h"

#include <OpenImageIO/filesystem.h>
#include <algorithm>

#include "cli/user_error.h"

namespace darkroom::cli {

namespace {

namespace Filesystem = OIIO::Filesystem;

// A run of two or more '#' means one digit each; OpenImageIO reads '@' that way.
std::string hashes_as_digits(const std::string& path) {
    std::string out = path;
    for (size_t start = out.find('#'); start != std::string::npos; start = out.find('#', start + 1)) {
        size_t end = out.find_first_not_of('#', start);
        if (end == std::string::npos) end = out.size();
        if (end - start >= 2) out.replace(start, end - start, std::string(end - start, '@'));
        start = end - 1;
    }
    return out;
}

struct Pattern {
    bool is_sequence = false;
    std::string printf_pattern;  // e.g. "plate.%04d.exr"
    std::string framespec;       // a range written in the name, e.g. "1-100"
};

Pattern parse(const std::string& path, int framepadding) {
    Pattern p;
    p.is_sequence = Filesystem::parse_pattern(hashes_as_digits(path).c_str(), framepadding, p.printf_pattern,
                                              p.framespec);
    return p;
}

std::vector<int> enumerate(const std::string& framespec) {
    std::vector<int> frames;
    if (!Filesystem::enumerate_sequence(framespec, frames) || frames.empty())
        throw UserError("--frames '" + framespec + "' is not a frame range (e.g. 1-100, 1-100x2, 1,5,9-12)");
    return frames;
}

std::vector<std::string> names(const Pattern& p, const std::vector<int>& frames) {
    std::vector<std::string> out;
    Filesystem::enumerate_file_sequence(p.printf_pattern, frames, out);
    return out;
}

// The frames between the first and last of `found` (ascending) that are not in it.
std::vector<int> gaps(const std::vector<int>& found) {
    std::vector<int> missing;
    for (size_t i = 1; i < found.size(); ++i)
        for (int f = found[i - 1] + 1; f < found[i]; ++f) missing.push_back(f);
    return missing;
}

}  // namespace

std::string frame_ranges(const std::vector<int>& frames) {
    std::string text;
    for (size_t start = 0, end; start < frames.size(); start = end) {
        for (end = start + 1; end < frames.size() && frames[end] == frames[end - 1] + 1;) ++end;
        text += (text.empty() ? "" : ", ") + std::to_string(frames[start]);
        if (end - start > 1) text += "-" + std::to_string(frames[end - 1]);
    }
    return text;
}

bool is_sequence_pattern(const std::string& path) { return parse(path, 0).is_sequence; }

ExpandedFrames expand_frames(const std::string& input, const std::string& output, const SequenceOptions& sequence,
                             int single_frame) {
    const Pattern in = parse(input, sequence.framepadding), out = parse(output, sequence.framepadding);
    if (!in.is_sequence && !out.is_sequence) {
        if (!sequence.frames.empty())
            throw UserError("--frames needs a frame number wildcard (#, @ or %0Nd) in the output name '" + output +
                            "'");
        return {{{single_frame, input, output}}, ""};
    }
    if (in.is_sequence && !out.is_sequence)
        throw UserError("the input '" + input + "' is a sequence: the output '" + output +
                        "' needs a frame number wildcard too (#, @ or %0Nd)");

    std::vector<int> frames;
    std::string missing_frames;
    if (!sequence.frames.empty()) {
        frames = enumerate(sequence.frames);
    } else if (!in.framespec.empty() || !out.framespec.empty()) {
        frames = enumerate(in.framespec.empty() ? out.framespec : in.framespec);
    } else if (in.is_sequence) {
        std::vector<std::string> found;
        Filesystem::scan_for_matching_filenames(in.printf_pattern, frames, found);
        if (frames.empty())
            throw UserError("no files match the input sequence '" + input + "' (" + in.printf_pattern +
                            "); name the frames with --frames");
        std::sort(frames.begin(), frames.end());
        missing_frames = frame_ranges(gaps(frames));
    } else {
        throw UserError("the output '" + output + "' is a sequence of a single input: name the frames with --frames");
    }

    const std::vector<std::string> outputs = names(out, frames);
    const std::vector<std::string> inputs = in.is_sequence ? names(in, frames) : std::vector<std::string>();
    ExpandedFrames expanded{{}, missing_frames};
    for (size_t i = 0; i < frames.size(); ++i)
        expanded.jobs.push_back({frames[i], in.is_sequence ? inputs[i] : input, outputs[i]});
    return expanded;
}

}  // namespace darkroom::cli
