#include "clients/tools/estimate/pose_csv.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <sstream>

#include "libs/core/csv_fields.h"
#include "libs/core/error.h"

namespace shapesense {
namespace {

struct NumberedLine {
  int number;  // 1-based line of the file
  std::string text;
};

// The lines that carry data: not blank, not comments.
std::vector<NumberedLine> ContentLines(const std::string& text) {
  std::vector<NumberedLine> lines;
  std::stringstream stream(text);
  std::string line;
  for (int number = 1; std::getline(stream, line); ++number) {
    const std::string trimmed = TrimBlanks(line);
    if (!trimmed.empty() && trimmed.front() != '#') lines.push_back({number, trimmed});
  }
  return lines;
}

// "y3", "tau0", ... (built by appending: GCC 12 warns falsely on "y" + string).
std::string TendonColumn(const char* prefix, int index) {
  std::string name(prefix);
  name += std::to_string(index);
  return name;
}

std::vector<std::string> RequiredColumns(int num_tendons, bool with_tensions) {
  std::vector<std::string> columns;
  for (int i = 0; i < num_tendons; ++i) columns.push_back(TendonColumn("y", i));
  for (const char* name : kConfigurationNames) columns.push_back(name);
  for (int i = 0; with_tensions && i < num_tendons; ++i) columns.push_back(TendonColumn("tau", i));
  return columns;
}

// The tendon index of a column named y<i> or tau<i>, or -1 for any other name.
long TendonIndexOfColumn(const std::string& name) {
  for (const std::string prefix : {"y", "tau"}) {
    const std::string digits = name.substr(std::min(prefix.size(), name.size()));
    if (name.rfind(prefix, 0) == 0 && !digits.empty() && digits.size() <= 6 &&
        digits.find_first_not_of("0123456789") == std::string::npos) {
      return std::stol(digits);
    }
  }
  return -1;
}

// Column name -> field index, checked against the model's tendon count.
std::map<std::string, int> ParseHeader(const NumberedLine& header, const std::string& source,
                                       int num_tendons, bool with_tensions) {
  const std::string where = "line " + std::to_string(header.number) + " (header)";
  std::map<std::string, int> columns;
  const std::vector<std::string> names = SplitCsvFields(header.text);
  for (size_t i = 0; i < names.size(); ++i) {
    if (!columns.emplace(names[i], static_cast<int>(i)).second) {
      throw InputError(DescribeInputError(source, where, "column '" + names[i] + "' repeats"));
    }
    if (TendonIndexOfColumn(names[i]) >= num_tendons) {
      throw InputError(DescribeInputError(source, where,
                                          "column '" + names[i] + "', but the model has " +
                                              std::to_string(num_tendons) + " tendons"));
    }
  }
  for (const std::string& name : RequiredColumns(num_tendons, with_tensions)) {
    if (!columns.contains(name)) {
      throw InputError(DescribeInputError(source, where, "missing column '" + name + "'"));
    }
  }
  return columns;
}

double ParseNumber(const std::string& field, const std::string& source, const std::string& where) {
  double value = 0.0;
  const char* end = field.data() + field.size();
  const auto [stop, error] = std::from_chars(field.data(), end, value);
  if (field.empty() || error != std::errc() || stop != end || !std::isfinite(value)) {
    throw InputError(DescribeInputError(source, where, "expected a number, got '" + field + "'"));
  }
  return value;
}

PoseSample ParsePose(const NumberedLine& line, const std::map<std::string, int>& columns,
                     const std::string& source, int num_tendons, bool with_tensions) {
  const std::string where = "line " + std::to_string(line.number);
  const std::vector<std::string> fields = SplitCsvFields(line.text);
  if (fields.size() != columns.size()) {
    throw InputError(DescribeInputError(source, where,
                                        "expected " + std::to_string(columns.size()) +
                                            " fields, got " + std::to_string(fields.size())));
  }
  const auto value = [&](const std::string& name) {
    return ParseNumber(fields[static_cast<size_t>(columns.at(name))], source, where + ": " + name);
  };
  PoseSample pose;
  pose.displacements.resize(num_tendons);
  for (int i = 0; i < num_tendons; ++i) pose.displacements(i) = value(TendonColumn("y", i));
  for (int j = 0; j < 4; ++j) {
    pose.configuration(j) = value(kConfigurationNames[static_cast<size_t>(j)]);
  }
  if (with_tensions) {
    pose.tensions.resize(num_tendons);
    for (int i = 0; i < num_tendons; ++i) pose.tensions(i) = value(TendonColumn("tau", i));
  }
  return pose;
}

}  // namespace

std::vector<PoseSample> ParsePoseCsv(const std::string& text, const std::string& source,
                                     int num_tendons, bool with_tensions) {
  const std::vector<NumberedLine> lines = ContentLines(text);
  if (lines.empty()) throw InputError(source + ": empty: expected a header line and poses");
  const std::map<std::string, int> columns =
      ParseHeader(lines.front(), source, num_tendons, with_tensions);
  std::vector<PoseSample> poses;
  for (size_t i = 1; i < lines.size(); ++i) {
    poses.push_back(ParsePose(lines[i], columns, source, num_tendons, with_tensions));
  }
  return poses;
}

std::string FormatPoseCsv(const std::vector<PoseSample>& poses) {
  if (poses.empty()) return "";
  const int n = static_cast<int>(poses.front().displacements.size());
  bool with_tensions = true;
  for (const PoseSample& pose : poses) with_tensions &= pose.tensions.size() == n;
  const std::vector<std::string> columns = RequiredColumns(n, with_tensions);
  std::ostringstream out;
  out.precision(17);
  for (size_t c = 0; c < columns.size(); ++c) out << (c ? "," : "") << columns[c];
  out << "\n";
  for (const PoseSample& pose : poses) {
    for (int i = 0; i < n; ++i) out << pose.displacements(i) << ",";
    out << pose.configuration(0) << "," << pose.configuration(1) << "," << pose.configuration(2)
        << "," << pose.configuration(3);
    for (int i = 0; with_tensions && i < n; ++i) out << "," << pose.tensions(i);
    out << "\n";
  }
  return out.str();
}

}  // namespace shapesense
