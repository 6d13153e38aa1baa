// Which known name a misspelt one was meant to be: the suggestion of an "unknown ~param"
// warning. ROS-free.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace follow_bot_common {

// The optimal-string-alignment distance: the fewest insertions, deletions, substitutions and
// swaps of two neighbouring characters (the usual typos) that turn `a` into `b`.
std::size_t editDistance(const std::string& a, const std::string& b);

// The name in `known` nearest to `typed` by editDistance, when one edit or at most a third of the
// longer of the two makes the difference (so `max_liner` finds `max_linear`, `Kp` finds `kp`, but
// `band_top_fraction` finds no unrelated name); the first such in `known` on a tie; nullopt when
// none is that close.
std::optional<std::string> nearestName(const std::string& typed,
                                       const std::vector<std::string>& known);

}  // namespace follow_bot_common
