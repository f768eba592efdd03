#pragma once

#include <cmath>
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

// An interval of accepted values; an open end excludes its bound.
struct Range {
  double low = -HUGE_VAL;
  double high = HUGE_VAL;
  bool low_open = false;
  bool high_open = false;

  bool Contains(double value) const {
    return std::isfinite(value) && (low_open ? value > low : value >= low) &&
           (high_open ? value < high : value <= high);
  }
  // "a number in [0, 1]", "a number in (0, 0.9]".
  std::string Describe() const {
    return std::string("a number in ") + (low_open ? "(" : "[") + Number(low) + ", " +
           Number(high) + (high_open ? ")" : "]");
  }
};

// "" when `value` is finite and within `range`, else
// "key: expected <what>, got <value>"; `what` defaults to the range.
inline std::string ExpectWithin(const std::string& key, double value, const Range& range,
                                const std::string& what = {}) {
  if (range.Contains(value)) return {};
  return Expected(key, what.empty() ? range.Describe() : what, Number(value));
}

// "" when `value` is finite, else "key: expected a finite number, got nan".
inline std::string ExpectFinite(const std::string& key, double value) {
  if (std::isfinite(value)) return {};
  return Expected(key, "a finite number", Number(value));
}

}  // namespace shapesense
