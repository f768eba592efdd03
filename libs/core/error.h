#pragma once

#include <stdexcept>
#include <string>

namespace shapesense {

// Input the system cannot use: a malformed file, a bad config value, a dataset
// that is missing a part. The message names what is wrong and where, e.g.
// "config/carving.yaml: voxel_size: expected a positive number, got -1".
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Formats "source: key: what" the same way everywhere.
inline std::string DescribeInputError(const std::string& source, const std::string& key,
                                      const std::string& what) {
  return source + ": " + key + ": " + what;
}

}  // namespace shapesense
