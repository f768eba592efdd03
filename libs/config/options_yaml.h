#pragma once

// Binds option structs to YAML. An options struct lists its fields once:
//
//   struct CarvingOptions {
//     double voxel_size = 1.0;
//     template <class Visitor> void VisitFields(Visitor&& visit) {
//       visit("voxel_size", voxel_size, "edge of one voxel, mm");
//     }
//     std::string Validate() const;  // empty, or "key: expected ..., got ..."
//   };
//
// and gets reading (unknown keys and wrong types rejected, missing keys keep
// their documented defaults), validation and writing for free. Errors are
// InputError("source: key: what"). Parsing works on YAML nodes; reading the
// file is the caller's job (runtime/config_file.h).

#include <yaml-cpp/yaml.h>

#include <array>
#include <charconv>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "libs/core/error.h"

namespace shapesense {
namespace options_detail {

template <class T>
concept HasFields = requires(T& t) {
  t.VisitFields([](const char*, auto&, const char*) {});
};

template <class T>
struct IsStdArray : std::false_type {};
template <class T, size_t N>
struct IsStdArray<std::array<T, N>> : std::true_type {};

template <class T>
struct IsStdVector : std::false_type {};
template <class T, class A>
struct IsStdVector<std::vector<T, A>> : std::true_type {};

template <class T>
std::string ExpectedName() {
  if constexpr (std::is_same_v<T, bool>)
    return "true or false";
  else if constexpr (std::is_integral_v<T>)
    return "an integer";
  else if constexpr (std::is_floating_point_v<T>)
    return "a number";
  else if constexpr (std::is_same_v<T, std::string>)
    return "a string";
  else if constexpr (IsStdArray<T>::value)
    return "a sequence of " + std::to_string(std::tuple_size_v<T>) + " " +
           ExpectedName<typename T::value_type>() + "s";
  else if constexpr (IsStdVector<T>::value)
    return "a sequence of " + ExpectedName<typename T::value_type>() + "s";
  else
    return "a map";
}

template <class T>
void Read(const YAML::Node& node, T& value, const std::string& source, const std::string& key);

template <class T>
void ReadFields(const YAML::Node& node, T& options, const std::string& source,
                const std::string& prefix) {
  if (!node.IsMap())
    throw InputError(
        DescribeInputError(source, prefix.empty() ? "(top level)" : prefix, "expected a map"));
  std::set<std::string> known;
  options.VisitFields([&](const char* key, auto& field, const char*) {
    known.insert(key);
    if (const YAML::Node child = node[key]) Read(child, field, source, prefix + key);
  });
  for (const auto& entry : node) {
    const std::string key = entry.first.as<std::string>();
    if (!known.contains(key)) {
      throw InputError(DescribeInputError(source, prefix + key, "unknown key"));
    }
  }
}

template <class T>
void Read(const YAML::Node& node, T& value, const std::string& source, const std::string& key) {
  if constexpr (HasFields<T>) {
    ReadFields(node, value, source, key + ".");
  } else if constexpr (IsStdArray<T>::value || IsStdVector<T>::value) {
    bool size_ok = true;
    if constexpr (IsStdArray<T>::value) size_ok = node.size() == std::tuple_size_v<T>;
    if (!node.IsSequence() || !size_ok) {
      throw InputError(DescribeInputError(source, key, "expected " + ExpectedName<T>()));
    }
    if constexpr (IsStdVector<T>::value) value.resize(node.size());
    for (size_t i = 0; i < node.size(); ++i) {
      Read(node[i], value[i], source, key + "[" + std::to_string(i) + "]");
    }
  } else {
    try {
      if (!node.IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "not a scalar");
      value = node.as<T>();
    } catch (const YAML::Exception&) {
      throw InputError(DescribeInputError(source, key, "expected " + ExpectedName<T>()));
    }
  }
}

// `readable`: doubles in their shortest exact form (0.3, not
// 0.29999999999999999), for files people read; both read back exactly.
template <class T>
YAML::Node Write(const T& value, bool readable = false) {
  if constexpr (HasFields<T>) {
    YAML::Node node(YAML::NodeType::Map);
    const_cast<T&>(value).VisitFields(
        [&](const char* key, auto& field, const char*) { node[key] = Write(field, readable); });
    return node;
  } else if constexpr (IsStdArray<T>::value || IsStdVector<T>::value) {
    YAML::Node node(YAML::NodeType::Sequence);
    for (const auto& element : value) node.push_back(Write(element, readable));
    node.SetStyle(YAML::EmitterStyle::Flow);
    return node;
  } else if constexpr (std::is_floating_point_v<T>) {
    if (!readable) return YAML::Node(value);
    // The shortest text that reads back to exactly the same double.
    std::array<char, 32> text{};
    const auto result = std::to_chars(text.data(), text.data() + text.size(), value);
    return YAML::Node(std::string(text.data(), result.ptr));
  } else {
    return YAML::Node(value);
  }
}

}  // namespace options_detail

// Reads options from a YAML map; keys not given keep their defaults. Throws
// InputError naming `source` and the key on an unknown key, a wrong type or a
// value that fails the struct's Validate().
template <class Options>
Options OptionsFromYaml(const YAML::Node& node, const std::string& source) {
  Options options;
  if (node && !node.IsNull()) options_detail::ReadFields(node, options, source, "");
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError(source + ": " + error);
  }
  return options;
}

template <class Options>
Options OptionsFromYamlText(const std::string& text, const std::string& source) {
  YAML::Node node;
  try {
    node = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(source + ": not valid YAML: " + e.what());
  }
  return OptionsFromYaml<Options>(node, source);
}

template <class Options>
YAML::Node OptionsToYaml(const Options& options) {
  return options_detail::Write(options);
}

// YAML text with each key's documentation as a comment above it.
template <class Options>
std::string OptionsToDocumentedYaml(const Options& options, int indent = 0) {
  std::string out;
  const std::string pad(static_cast<size_t>(indent), ' ');
  const_cast<Options&>(options).VisitFields([&](const char* key, auto& field, const char* doc) {
    out += pad + "# " + doc + "\n";
    if constexpr (options_detail::HasFields<std::decay_t<decltype(field)>>) {
      out += pad + key + ":\n" + OptionsToDocumentedYaml(field, indent + 2);
    } else {
      YAML::Emitter emitter;
      emitter << options_detail::Write(field, /*readable=*/true);
      out += pad + key + ": " + emitter.c_str() + "\n";
    }
  });
  return out;
}

}  // namespace shapesense
