#pragma once
// Help generated from the commands' option declarations (args.hpp): `knnocc <command> --help`
// as text, and docs/cli.md (`knnocc help --markdown`) as Markdown. Both come from the same
// CommandSpec, so neither can drift from what the parser accepts.

#include <string>
#include <vector>

#include "args.hpp"

namespace knnocc::cli {

namespace detail {

constexpr std::size_t kHelpWidth = 100;  // columns of --help
constexpr std::size_t kHelpIndent = 24;  // where an option's description starts

/// Appends `text` word-wrapped at kHelpWidth, continuation lines indented by `indent`; a '\n'
/// in `text` starts a new (indented) line. `column` is where the first word starts.
inline void wrap(std::string& out, const std::string& text, std::size_t column,
                 std::size_t indent) {
  std::size_t at = column;
  std::size_t i = 0;
  bool line_start = true;
  while (i < text.size()) {
    if (text[i] == '\n') {
      out += '\n' + std::string(indent, ' ');
      at = indent;
      line_start = true;
      ++i;
      continue;
    }
    if (text[i] == ' ') {
      ++i;
      continue;
    }
    std::size_t end = i;
    while (end < text.size() && text[end] != ' ' && text[end] != '\n') ++end;
    const std::size_t len = end - i;
    if (!line_start && at + 1 + len > kHelpWidth) {
      out += '\n' + std::string(indent, ' ');
      at = indent;
      line_start = true;
    }
    if (!line_start) {
      out += ' ';
      ++at;
    }
    out.append(text, i, len);
    at += len;
    line_start = false;
    i = end;
  }
}

/// "(default X; in [a, b])", "(required)", or "".
inline std::string option_notes(const Option& o) {
  std::vector<std::string> notes;
  if (o.is_required()) notes.push_back("required");
  if (!o.default_shown().empty()) notes.push_back("default " + o.default_shown());
  const std::string range = o.range_text();
  if (!range.empty() && o.choices().empty()) notes.push_back(range);
  std::string s;
  for (std::size_t i = 0; i < notes.size(); ++i) s += (i ? "; " : "") + notes[i];
  return s.empty() ? s : "(" + s + ")";
}

/// "-r, --res R" / "--discretize" / "--model octomap|knn|robust".
inline std::string option_words(const Option& o) {
  std::string s = o.short_form().empty() ? "" : o.short_form() + ", ";
  s += o.name();
  if (!o.takes_value()) return s;
  if (!o.choices().empty()) {
    s += ' ';
    for (std::size_t i = 0; i < o.choices().size(); ++i) s += (i ? "|" : "") + o.choices()[i];
    return s;
  }
  return s + ' ' + o.value_name();
}

inline std::string markdown_cell(std::string s) {
  std::string out;
  for (const char c : s) {
    if (c == '|')
      out += "\\|";
    else if (c == '\n')
      out += ' ';
    else
      out += c;
  }
  return out;
}

}  // namespace detail

/// `knnocc <command> --help`.
inline std::string help_text(const CommandSpec& spec) {
  std::string out = "usage: " + spec.usage + "\n";
  if (!spec.text.empty()) out += "\n" + spec.text;
  for (const OptionGroup& g : spec.groups) {
    out += "\n" + g.title + ":\n";
    if (!g.text.empty()) out += g.text;
    for (const Option& o : g.options) {
      std::string line = "  " + detail::option_words(o);
      if (line.size() + 2 > detail::kHelpIndent)
        line += "\n" + std::string(detail::kHelpIndent, ' ');
      else
        line += std::string(detail::kHelpIndent - line.size(), ' ');
      const std::string notes = detail::option_notes(o);
      detail::wrap(line, o.help() + (notes.empty() ? "" : " " + notes), detail::kHelpIndent,
                   detail::kHelpIndent);
      out += line + "\n";
    }
  }
  if (!spec.footer.empty()) out += "\n" + spec.footer;
  return out;
}

/// One command's section of docs/cli.md.
inline std::string markdown_section(const CommandSpec& spec) {
  std::string out =
      "## knnocc " + spec.name + "\n\n" + spec.summary + "\n\n```text\nusage: " + spec.usage + "\n";
  if (!spec.text.empty()) out += "\n" + spec.text;
  out += "```\n";
  for (const OptionGroup& g : spec.groups) {
    out += "\n### " + spec.name + ": " + g.title + "\n\n";
    if (!g.text.empty()) out += "```text\n" + g.text + "```\n\n";
    out += "| option | default | allowed | meaning |\n| --- | --- | --- | --- |\n";
    for (const Option& o : g.options) {
      std::string def = o.is_required() ? "required" : o.default_shown();
      out += "| `" + detail::option_words(o) + "` | " + detail::markdown_cell(def) + " | " +
             detail::markdown_cell(o.range_text()) + " | " + detail::markdown_cell(o.help()) +
             " |\n";
    }
  }
  if (!spec.footer.empty()) out += "\n```text\n" + spec.footer + "```\n";
  return out + "\n";
}

}  // namespace knnocc::cli
