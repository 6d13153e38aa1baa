#include "follow_bot_common/nearest_name.h"

#include <algorithm>

namespace follow_bot_common {

std::size_t editDistance(const std::string& a, const std::string& b) {
  // Three rows of the dynamic-programming table: the swap looks two rows back.
  std::vector<std::size_t> before(b.size() + 1), previous(b.size() + 1), current(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t substitution = previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, substitution});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        current[j] = std::min(current[j], before[j - 2] + 1);
      }
    }
    std::swap(before, previous);
    std::swap(previous, current);
  }
  return previous[b.size()];
}

std::optional<std::string> nearestName(const std::string& typed,
                                       const std::vector<std::string>& known) {
  std::optional<std::string> nearest;
  std::size_t nearest_distance = 0;
  for (const std::string& name : known) {
    const std::size_t distance = editDistance(typed, name);
    const std::size_t longer = std::max(typed.size(), name.size());
    const bool close_enough = distance <= std::max<std::size_t>(1, longer / 3);
    if (close_enough && (!nearest || distance < nearest_distance)) {
      nearest = name;
      nearest_distance = distance;
    }
  }
  return nearest;
}

}  // namespace follow_bot_common
