#pragma once

// The small CSV dialect of the project's input files (poses, points,
// targets): comma-separated fields, blanks around a field ignored, no quoting.
#include <sstream>
#include <string>
#include <vector>

namespace shapesense {

// `text` without leading and trailing blanks (space, tab, CR).
inline std::string TrimBlanks(const std::string& text) {
  const size_t begin = text.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  return text.substr(begin, text.find_last_not_of(" \t\r") - begin + 1);
}

// The trimmed fields of one line; a trailing comma gives a last empty field.
inline std::vector<std::string> SplitCsvFields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  std::string field;
  while (std::getline(stream, field, ',')) fields.push_back(TrimBlanks(field));
  if (!line.empty() && line.back() == ',') fields.push_back("");
  return fields;
}

}  // namespace shapesense
