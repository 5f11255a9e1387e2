#include "cli/sequence.h"

#include <OpenImageIO/filesystem.h>

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

}  // namespace

bool is_sequence_pattern(const std::string& path) { return parse(path, 0).is_sequence; }

std::vector<FrameJob> expand_frames(const std::string& input, const std::string& output,
                                    const SequenceOptions& sequence, int single_frame) {
    const Pattern in = parse(input, sequence.framepadding), out = parse(output, sequence.framepadding);
    if (!in.is_sequence && !out.is_sequence) {
        if (!sequence.frames.empty())
            throw UserError("--frames needs a frame number wildcard (#, @ or %0Nd) in the output name '" + output +
                            "'");
        return {{single_frame, input, output}};
    }
    if (in.is_sequence && !out.is_sequence)
        throw UserError("the input '" + input + "' is a sequence: the output '" + output +
                        "' needs a frame number wildcard too (#, @ or %0Nd)");

    std::vector<int> frames;
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
    } else {
        throw UserError("the output '" + output + "' is a sequence of a single input: name the frames with --frames");
    }

    const std::vector<std::string> outputs = names(out, frames);
    const std::vector<std::string> inputs = in.is_sequence ? names(in, frames) : std::vector<std::string>();
    std::vector<FrameJob> jobs;
    for (size_t i = 0; i < frames.size(); ++i)
        jobs.push_back({frames[i], in.is_sequence ? inputs[i] : input, outputs[i]});
    return jobs;
}

}  // namespace darkroom::cli
