// Helpers of the tests that detect coloured blobs (colour_blobs_test, beacon_controller_test).
#pragma once

#include <stdexcept>
#include <string>

#include "follow_bot/colour_blobs.h"

namespace follow_bot::test {

// A copy, so that callers may pass a temporary result.
inline ColourBlob blobOf(const BlobResult& result, const std::string& name) {
  const ColourBlob* blob = result.find(name);
  if (blob == nullptr) throw std::runtime_error("no colour " + name);
  return *blob;
}

// The default colours, any shape: no roundness gate.
inline ColourBlobConfig anyShape() {
  ColourBlobConfig config;
  config.roundness_tolerance = 0.0;
  return config;
}

}  // namespace follow_bot::test
