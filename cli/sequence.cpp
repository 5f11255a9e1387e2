#include "cli/sequence.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>
#include <algorithm>
#include <cmath>
#include <cstdio>

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

// How many frames `framespec` names, counted without listing them (as OpenImageIO's parser
// would, into memory): "1-100000000" is 100 million; 0 where it is not a range it reads.
double frame_count(const std::string& framespec) {
    double count = 0;
    for (const std::string& part : OIIO::Strutil::splits(framespec, ",")) {
        long long first = 0, last = 0, step = 1;
        char kind = 'x';
        const int read = std::sscanf(part.c_str(), "%lld-%lld%c%lld", &first, &last, &kind, &step);
        if (read < 2) {
            ++count;
            continue;
        }
        const double span = std::abs(double(last) - double(first)) + 1;
        const double every = read == 4 && step > 0 ? std::ceil(span / double(step)) : span;
        count += kind == 'y' && read == 4 ? span - every : every;
    }
    return count;
}

std::vector<int> enumerate(const std::string& framespec) {
    if (frame_count(framespec) > kMaxFrames)
        throw UserError("--frames '" + framespec + "' names more than " + std::to_string(kMaxFrames) +
                        " frames, the most a run takes: split it into several runs");
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

// The frames between the first and last of `found` (ascending) that are not in it, as
// ranges ("6, 9-11"), without listing them: two files numbered 1 and 99999999 leave
// a gap of a hundred million.
std::string gaps(const std::vector<int>& found) {
    std::string text;
    for (size_t i = 1; i < found.size(); ++i) {
        const long long first = found[i - 1] + 1LL, last = found[i] - 1LL;
        if (first > last) continue;
        text += (text.empty() ? "" : ", ") + std::to_string(first) + (last > first ? "-" + std::to_string(last) : "");
    }
    return text;
}

}  // namespace

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
        missing_frames = gaps(frames);
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
