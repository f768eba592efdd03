#pragma once

#include <sstream>
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

// A number in a message as people read it: the stream's default form
// ("0.5", "1e-06", "nan"), six significant digits.
inline std::string Number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// "key: expected what, got got": the one shape of a validation message.
template <class T>
std::string Expected(const std::string& key, const std::string& what, const T& got) {
  std::ostringstream out;
  out << key << ": expected " << what << ", got " << got;
  return out.str();
}

}  // namespace shapesense
