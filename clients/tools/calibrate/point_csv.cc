#include "clients/tools/calibrate/point_csv.h"

#include <cmath>
#include <optional>
#include <sstream>

#include "libs/core/csv_fields.h"
#include "libs/core/error.h"

namespace shapesense {
namespace {

std::optional<double> ParseNumber(const std::string& text) {
  if (text.empty()) return std::nullopt;
  size_t used = 0;
  try {
    const double value = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(value)) return std::nullopt;
    return value;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// The point on a line of 3 or 4 fields; nullopt when the numbers are not numbers.
std::optional<NamedPoint> ParseFields(const std::vector<std::string>& fields) {
  const size_t first = fields.size() == 4 ? 1 : 0;
  NamedPoint point;
  if (first == 1) point.name = fields[0];
  for (size_t k = 0; k < 3; ++k) {
    const std::optional<double> value = ParseNumber(fields[first + k]);
    if (!value) return std::nullopt;
    point.position[static_cast<Eigen::Index>(k)] = *value;
  }
  return point;
}

}  // namespace

std::vector<NamedPoint> ParsePointCsv(const std::string& text, const std::string& source) {
  std::vector<NamedPoint> points;
  std::stringstream stream(text);
  int line_number = 0;
  bool first_content = true;
  for (std::string line; std::getline(stream, line);) {
    ++line_number;
    line = TrimBlanks(line);
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> fields = SplitCsvFields(line);
    const std::string where = source + ":" + std::to_string(line_number);
    if (fields.size() != 3 && fields.size() != 4) {
      throw InputError(where + ": expected x,y,z or name,x,y,z (mm), got " +
                       std::to_string(fields.size()) + " fields");
    }
    const std::optional<NamedPoint> point = ParseFields(fields);
    const bool header = first_content && !point;
    first_content = false;
    if (header) continue;
    if (!point) {
      std::string message = where;
      message.append(": expected numbers for x,y,z (mm), got '").append(line).append("'");
      throw InputError(message);
    }
    if (!points.empty() && points.front().name.empty() != point->name.empty()) {
      throw InputError(where + ": mixes x,y,z and name,x,y,z lines");
    }
    points.push_back(*point);
  }
  if (points.empty()) throw InputError(source + ": no points");
  return points;
}

}  // namespace shapesense
