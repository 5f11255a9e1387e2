// "Did you mean ...?" for a name that is not one of the known ones (a stock id, a
// subcommand): the known names a typo away from it.
#pragma once

#include <algorithm>
#include <cctype>
#include <string>
#include <vector>

namespace darkroom {

// Edits (insertions, deletions, substitutions, swaps of neighbours) between `a` and `b`,
// letter case ignored: "kodak-vison3" is one from "kodak-vision3", "Devlop" one from "develop".
inline size_t edit_distance(const std::string& a, const std::string& b) {
    auto same = [](char x, char y) { return std::tolower((unsigned char)x) == std::tolower((unsigned char)y); };
    // Three rows of the table suffice: a swap looks two back.
    std::vector<size_t> before(b.size() + 1), previous(b.size() + 1), current(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) previous[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        current[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            current[j] = std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + !same(a[i - 1], b[j - 1])});
            if (i > 1 && j > 1 && same(a[i - 1], b[j - 2]) && same(a[i - 2], b[j - 1]))
                current[j] = std::min(current[j], before[j - 2] + 1);
        }
        std::swap(before, previous);
        std::swap(previous, current);
    }
    return previous[b.size()];
}

// The known names nearest `typed`, if they are near enough to be a typo of it: a third of
// its letters at most (at least one edit), so that a short unrelated word suggests nothing.
inline std::vector<std::string> close_names(const std::string& typed, const std::vector<std::string>& known) {
    size_t best = std::max<size_t>(1, typed.size() / 3);
    std::vector<std::string> nearest;
    for (const std::string& name : known) {
        const size_t d = edit_distance(typed, name);
        if (d > best) continue;
        if (d < best) nearest.clear();
        best = d;
        nearest.push_back(name);
    }
    return nearest;
}

// "did you mean 'develop'?" (or "'a' or 'b'"), or "" when no known name is near `typed`.
inline std::string did_you_mean(const std::string& typed, const std::vector<std::string>& known) {
    const std::vector<std::string> nearest = close_names(typed, known);
    std::string names;
    for (size_t i = 0; i < nearest.size(); ++i)
        names += (i == 0 ? "" : i + 1 == nearest.size() ? " or " : ", ") + ("'" + nearest[i] + "'");
    return names.empty() ? "" : "did you mean " + names + "?";
}

}  // namespace darkroom
