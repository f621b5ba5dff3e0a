/// @file launch_substitution.cc
/// @brief Substitution of `$(...)` expressions in launch file strings.
#include "tools/launch_substitution.h"

#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace p2i::tools {
namespace {

std::vector<std::string> SplitWords(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> words;
  std::string w;
  while (in >> w) words.push_back(w);
  return words;
}

std::string Dirname(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

std::string Evaluate(const std::string& expr, const SubstitutionScope& scope) {
  const std::vector<std::string> words = SplitWords(expr);
  if (words.empty()) throw std::invalid_argument("empty substitution '$()'");
  const std::string& kind = words[0];
  if (kind == "var") {
    if (words.size() != 2) {
      throw std::invalid_argument("'$(" + expr + ")' must be $(var NAME)");
    }
    const auto it = scope.vars.find(words[1]);
    if (it == scope.vars.end()) {
      std::string known;
      for (const auto& [name, value] : scope.vars) known += (known.empty() ? "" : ", ") + name;
      throw std::invalid_argument("unknown launch variable '" + words[1] +
                                  "' in '$(" + expr + ")' (declare it with an `arg` or `let`" +
                                  (known.empty() ? "" : "; known: " + known) + ")");
    }
    return it->second;
  }
  if (kind == "dirname" && words.size() == 1) return Dirname(scope.file);
  if (kind == "filename" && words.size() == 1) return scope.file;
  if (kind == "env" && (words.size() == 2 || words.size() == 3)) {
    const char* value = std::getenv(words[1].c_str());
    if (value != nullptr) return value;
    if (words.size() == 3) return words[2];
    throw std::invalid_argument("environment variable '" + words[1] +
                                "' is not set (give a default: $(env " + words[1] + " DEFAULT))");
  }
  throw std::invalid_argument("unsupported substitution '$(" + expr +
                              ")' (supported: $(var NAME), $(dirname), $(filename), "
                              "$(env NAME [DEFAULT]))");
}

}  // namespace

std::string Substitute(const std::string& text, const SubstitutionScope& scope) {
  std::string out;
  size_t pos = 0;
  while (pos < text.size()) {
    const size_t start = text.find("$(", pos);
    if (start == std::string::npos) {
      out.append(text, pos, std::string::npos);
      break;
    }
    out.append(text, pos, start - pos);
    const size_t end = text.find(')', start + 2);
    if (end == std::string::npos) {
      throw std::invalid_argument("unterminated substitution in '" + text + "' (missing ')')");
    }
    const std::string expr = text.substr(start + 2, end - start - 2);
    if (expr.find("$(") != std::string::npos) {
      throw std::invalid_argument("nested substitutions are not supported: '" + text + "'");
    }
    out += Evaluate(expr, scope);
    pos = end + 1;
  }
  return out;
}

}  // namespace p2i::tools
