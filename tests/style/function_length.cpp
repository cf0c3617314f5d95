// function_length: no function body in the given files is longer than a limit (lines between its
// braces; lambdas count towards the function that holds them).
//
// A light C++ scanner, enough for clang-formatted code: comments, string, character and raw
// string literals and preprocessor lines are skipped; a `{` opens a function body when the text
// before it (since the last `;`, `{` or `}`) holds a `)` and does not start with a control keyword
// (if, for, while, switch, catch, do, else) or `=` / `return` (a lambda or initializer outside a
// function).
//
// usage: function_length MAX_LINES FILE_OR_FOLDER...   (prints every violation; exit 1 if any)

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

struct Scope {
  bool function = false;
  std::size_t line = 0;  // where its `{` is
  std::string head;
};

bool starts_with_word(const std::string& s, const char* word) {
  const std::size_t n = std::char_traits<char>::length(word);
  return s.compare(0, n, word) == 0 &&
         (s.size() == n || !(std::isalnum(static_cast<unsigned char>(s[n])) || s[n] == '_'));
}

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

bool is_function_head(const std::string& raw) {
  const std::string h = trim(raw);
  if (h.find(')') == std::string::npos) return false;
  for (const char* w : {"if", "for", "while", "switch", "catch", "do", "else", "return"})
    if (starts_with_word(h, w)) return false;
  // `x = [..](..) {` or `Type x{f(a)}`-like initializers at namespace scope are not functions.
  return h.find('=') == std::string::npos || h.find("operator") != std::string::npos;
}

/// Reports the function bodies of `text` longer than `limit` lines; returns how many.
int check(const std::string& path, const std::string& text, std::size_t limit) {
  std::vector<Scope> scopes;
  std::string head;
  std::size_t line = 1;
  int in_function = 0;
  int bad = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      head += ' ';
      continue;
    }
    if (c == '#' && trim(head).empty()) {  // a preprocessor line (and its continuations)
      for (; i < text.size() && !(text[i] == '\n' && text[i - 1] != '\\'); ++i)
        if (text[i] == '\n') ++line;
      --i;
      continue;
    }
    if (c == '/' && i + 1 < text.size() && text[i + 1] == '/') {
      while (i < text.size() && text[i] != '\n') ++i;
      --i;
      continue;
    }
    if (c == '/' && i + 1 < text.size() && text[i + 1] == '*') {
      for (i += 2; i + 1 < text.size() && !(text[i] == '*' && text[i + 1] == '/'); ++i)
        if (text[i] == '\n') ++line;
      ++i;
      continue;
    }
    if (c == 'R' && i + 1 < text.size() && text[i + 1] == '"' &&
        (i == 0 ||
         !(std::isalnum(static_cast<unsigned char>(text[i - 1])) || text[i - 1] == '_'))) {
      const std::size_t open = text.find('(', i);
      const std::string close = ")" + text.substr(i + 2, open - i - 2) + "\"";
      const std::size_t end = text.find(close, open);
      for (std::size_t j = i; j < end && j < text.size(); ++j)
        if (text[j] == '\n') ++line;
      i = end == std::string::npos ? text.size() : end + close.size() - 1;
      head += "\"\"";
      continue;
    }
    if (c == '"' || c == '\'') {
      for (++i; i < text.size() && text[i] != c; ++i)
        if (text[i] == '\\') ++i;
      head += "\"\"";
      continue;
    }
    if (c == '{') {
      const bool fn = in_function == 0 && is_function_head(head);
      scopes.push_back({fn, line, trim(head)});
      in_function += fn;
      head.clear();
    } else if (c == '}') {
      if (scopes.empty()) continue;
      const Scope s = scopes.back();
      scopes.pop_back();
      if (s.function) {
        --in_function;
        const std::size_t body = line > s.line ? line - s.line - 1 : 0;
        if (body > limit) {
          std::printf("%s:%zu: function body of %zu lines (limit %zu): %.80s\n", path.c_str(),
                      s.line, body, limit, s.head.c_str());
          ++bad;
        }
      }
      head.clear();
    } else if (c == ';') {
      head.clear();
    } else {
      head += c;
    }
  }
  return bad;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: function_length MAX_LINES FILE_OR_FOLDER...\n");
    return 2;
  }
  const std::size_t limit = std::strtoul(argv[1], nullptr, 10);
  int bad = 0;
  std::size_t files = 0;
  auto scan = [&](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    bad += check(p.string(), ss.str(), limit);
    ++files;
  };
  for (int a = 2; a < argc; ++a) {
    const fs::path root(argv[a]);
    if (!fs::is_directory(root)) {
      scan(root);
      continue;
    }
    for (const auto& e : fs::recursive_directory_iterator(root)) {
      const std::string ext = e.path().extension().string();
      if (e.is_regular_file() && (ext == ".cpp" || ext == ".hpp")) scan(e.path());
    }
  }
  std::printf("%zu files, %d function bodies over %zu lines\n", files, bad, limit);
  return bad ? 1 : 0;
}
