// The benchmark programs' command-line parser (cli_args.h).
#include "cli_args.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace quadrant::cli {

namespace {

std::string Join(const std::vector<std::string>& items, const char* sep = ", ") {
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : sep) + item;
  return out;
}

std::string FormatDouble(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  return buffer;
}

/// The items of a comma-separated list, or nothing when one is empty ("a,,b", ",", ""): an empty
/// item is a typo, not a shorter list.
std::optional<std::vector<std::string>> SplitItems(const std::string& text) {
  std::vector<std::string> items;
  size_t start = 0;
  while (true) {
    const size_t end = text.find(',', start);
    items.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (items.back().empty()) return std::nullopt;
    if (end == std::string::npos) return items;
    start = end + 1;
  }
}

bool IsHelp(const char* arg) { return std::strcmp(arg, "--help") == 0 || std::strcmp(arg, "-h") == 0; }

}  // namespace

// ---- Option modifiers -------------------------------------------------------------------------

Option& Option::Default(std::string text) {
  default_ = std::move(text);
  return *this;
}

Option& Option::Accepts(std::string text) {
  accepts_ = std::move(text);
  return *this;
}

Option& Option::Value(std::string text) {
  value_ = std::move(text);
  return *this;
}

Option& Option::Check(ItemCheck check) {
  check_ = std::move(check);
  return *this;
}

Option& Option::AllowNone() {
  allowNone_ = true;
  accepts_ += ", or none";
  return *this;
}

Option& Option::Required() {
  required_ = true;
  return *this;
}

// ---- Declarations -----------------------------------------------------------------------------

Parser::Parser(std::string program, std::string summary) : program_(std::move(program)), summary_(std::move(summary)) {}

Option& Parser::Add(std::string name, std::string help, std::string value, std::string accepts, std::string def) {
  auto o = std::make_unique<Option>();
  o->name_ = std::move(name);
  o->help_ = std::move(help);
  o->value_ = std::move(value);
  o->accepts_ = std::move(accepts);
  o->default_ = std::move(def);
  options_.push_back(std::move(o));
  return *options_.back();
}

std::string Parser::IntAccepts(long long least, long long most) {
  return "an integer in [" + std::to_string(least) + ", " + std::to_string(most) + "]";
}

bool Parser::ParseInteger(const std::string& text, long long least, long long most, long long& out) {
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0 || v < least || v > most) return false;
  out = v;
  return true;
}

Option& Parser::Flag(std::string name, bool* target, std::string help) {
  Option& o = Add(std::move(name), std::move(help), "", "no value", "");
  o.takesValue_ = false;
  o.set_ = [target](const Option&, const std::string&) -> std::optional<std::string> {
    *target = true;
    return std::nullopt;
  };
  return o;
}

Option& Parser::Double(std::string name, double* target, double least, double most, std::string help) {
  Option& o = Add(std::move(name), std::move(help), "X",
                  "a number in [" + FormatDouble(least) + ", " + FormatDouble(most) + "]", FormatDouble(*target));
  o.set_ = [target, least, most](const Option&, const std::string& text) -> std::optional<std::string> {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || errno != 0 || !std::isfinite(v) || v < least || v > most) return "";
    *target = v;
    return std::nullopt;
  };
  return o;
}

Option& Parser::IntList(std::string name, std::vector<int>* target, int least, int most, std::string help) {
  std::vector<std::string> def;
  for (int v : *target) def.push_back(std::to_string(v));
  Option& o = Add(std::move(name), std::move(help), "N,...",
                  "a comma-separated list of integers in [" + std::to_string(least) + ", " + std::to_string(most) + "]",
                  Join(def, ","));
  o.set_ = [target, least, most](const Option&, const std::string& text) -> std::optional<std::string> {
    const std::optional<std::vector<std::string>> items = SplitItems(text);
    if (!items) return "an empty item";
    std::vector<int> values;
    for (const std::string& item : *items) {
      long long v = 0;
      if (!ParseInteger(item, least, most, v)) return items->size() > 1 ? "'" + item + "' is not " + IntAccepts(least, most) : "";
      values.push_back(int(v));
    }
    *target = std::move(values);
    return std::nullopt;
  };
  return o;
}

Option& Parser::String(std::string name, std::string* target, std::string value, std::string help) {
  Option& o = Add(std::move(name), help, std::move(value), help, *target);
  o.set_ = [target](const Option&, const std::string& text) -> std::optional<std::string> {
    *target = text;
    return std::nullopt;
  };
  return o;
}

Option& Parser::OutputDirectory(std::string name, std::string* target, std::string help) {
  Option& o = Add(std::move(name), std::move(help), "DIR", "a directory, or a path where one can be created", *target);
  o.set_ = [target](const Option&, const std::string& text) -> std::optional<std::string> {
    if (text.empty()) return "";
    std::error_code ec;
    std::filesystem::path at(text);
    // The nearest part of the path that exists must be a directory.
    while (!at.empty() && !std::filesystem::exists(at, ec)) {
      const std::filesystem::path parent = at.parent_path();
      if (parent == at) break;
      at = parent;
    }
    if (!at.empty() && std::filesystem::exists(at, ec) && !std::filesystem::is_directory(at, ec)) {
      return "'" + at.string() + "' is not a directory";
    }
    *target = text;
    return std::nullopt;
  };
  return o;
}

namespace {

/// The problem with one name, or nothing: not in `allowed` (when it is not empty), or refused by
/// the option's own check.
std::optional<std::string> CheckName(const std::string& item, const std::vector<std::string>& allowed,
                                     const std::string& noun, const ItemCheck& check) {
  if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), item) == allowed.end()) {
    return "unknown " + noun + " '" + item + "'";
  }
  if (check) {
    std::string problem = check(item);
    if (!problem.empty()) return problem;
  }
  return std::nullopt;
}

}  // namespace

Option& Parser::Name(std::string name, std::string* target, std::vector<std::string> allowed, std::string noun,
                     std::string help) {
  Option& o = Add(std::move(name), std::move(help), "NAME", allowed.empty() ? std::string(!noun.empty() && std::strchr("aeiou", noun[0]) ? "an " : "a ") + noun + " name" : "one of " + Join(allowed),
                  *target);
  o.set_ = [target, allowed, noun](const Option& self, const std::string& text) -> std::optional<std::string> {
    if (std::optional<std::string> problem = CheckName(text, allowed, noun, self.check_)) return problem;
    *target = text;
    return std::nullopt;
  };
  return o;
}

Option& Parser::NameList(std::string name, std::vector<std::string>* target, std::vector<std::string> allowed,
                         std::string noun, std::string help) {
  Option& o = Add(std::move(name), std::move(help), "a,b",
                  allowed.empty() ? "a comma-separated list of " + noun + "s"
                                  : "a comma-separated list of " + noun + "s from " + Join(allowed),
                  Join(*target, ","));
  o.set_ = [target, allowed, noun](const Option& self, const std::string& text) -> std::optional<std::string> {
    if (self.allowNone_ && text == "none") {
      target->clear();
      return std::nullopt;
    }
    const std::optional<std::vector<std::string>> items = SplitItems(text);
    if (!items) return "an empty item";
    for (const std::string& item : *items) {
      if (std::optional<std::string> problem = CheckName(item, allowed, noun, self.check_)) return problem;
    }
    *target = *items;
    return std::nullopt;
  };
  return o;
}

// ---- Behaviour --------------------------------------------------------------------------------

void Parser::PassThrough(std::string prefix, std::string epilogue) {
  passThrough_ = true;
  passPrefix_ = std::move(prefix);
  epilogue_ = std::move(epilogue);
}

void Parser::Epilogue(std::string text) { epilogue_ = std::move(text); }

void Parser::Quiet(bool quiet) { quiet_ = quiet; }

void Parser::OnExit(std::function<void(int status)> exit) { exit_ = std::move(exit); }

void Parser::Exit(int status) const {
  std::fflush(stdout);
  if (exit_) exit_(status);
  std::exit(status);
}

void Parser::Fail(const std::string& problem) const {
  if (!quiet_) std::fprintf(stderr, "%s: %s\n", program_.c_str(), problem.c_str());
  Exit(2);
}

Option& Parser::Find(std::string_view name) const {
  for (const std::unique_ptr<Option>& o : options_) {
    if (o->name_ == name) return *o;
  }
  std::fprintf(stderr, "%s: internal error: no option %.*s\n", program_.c_str(), int(name.size()), name.data());
  std::abort();
}

void Parser::FailOption(std::string_view name, const std::string& value, const std::string& problem) const {
  const Option& o = Find(name);
  Fail(o.name_ + ": " + (problem.empty() ? "" : problem + "; ") + o.accepts_ + " (got '" + value + "')");
}

void Parser::FailMissing(std::string_view name) const {
  const Option& o = Find(name);
  Fail(o.name_ + ": " + o.accepts_ + " (got nothing)");
}

bool Parser::Given(std::string_view name) const { return Find(name).given_; }

void Parser::PrintHelp(std::FILE* out) const {
  std::string usage = "usage: " + program_ + " [options]";
  for (const std::unique_ptr<Option>& o : options_) {
    if (!o->name_.starts_with("-")) usage += o->required_ ? " " + o->name_ : " [" + o->name_ + "]";
  }
  std::fprintf(out, "%s\n\n%s\n\noptions:\n", usage.c_str(), summary_.c_str());
  for (const std::unique_ptr<Option>& o : options_) {
    std::string left = "  " + o->name_;
    if (o->name_.starts_with("-") && o->takesValue_) left += " " + o->value_;
    std::string text = o->help_;
    if (o->takesValue_ && !o->accepts_.empty() && o->accepts_ != o->help_) text += ": " + o->accepts_;
    if (o->required_) text += " (required)";
    if (!o->default_.empty()) text += " (default " + o->default_ + ")";
    std::fprintf(out, "%-24s%s%s\n", left.c_str(), left.size() >= 24 ? "\n                        " : "", text.c_str());
  }
  std::fprintf(out, "%-24s%s\n", "  -h, --help", "print this help and exit");
  if (!epilogue_.empty()) std::fprintf(out, "\n%s\n", epilogue_.c_str());
}

std::string Parser::Accepted() const {
  std::vector<std::string> names, positionals;
  for (const std::unique_ptr<Option>& o : options_) {
    if (o->name_.starts_with("-")) {
      names.push_back(o->name_);
    } else {
      positionals.push_back(o->required_ ? o->name_ : "[" + o->name_ + "]");
    }
  }
  if (passThrough_) names.push_back("the flags of Google Benchmark");
  std::string text = Join(positionals, " ");
  if (!names.empty()) text += (text.empty() ? "" : "; options ") + Join(names);
  return " (accepted: " + (text.empty() ? std::string("nothing") : text) + ")";
}

void Parser::FailOnRest(int argc, char** argv) const {
  if (argc < 2) return;
  const std::string arg = argv[1];
  Fail(arg.substr(0, arg.find('=')) + ": a flag of Google Benchmark with a value it takes (got '" + arg + "')");
}

void Parser::Parse(int& argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (!IsHelp(argv[i])) continue;
    if (!quiet_) PrintHelp(stdout);
    if (!passThrough_) Exit(0);
    argv[1] = argv[i];  // the next parser prints its own help after this one
    argc = 2;
    argv[argc] = nullptr;
    std::fflush(stdout);
    return;
  }
  size_t positional = 0;  // the positional arguments taken so far
  int write = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (passThrough_ && arg.starts_with(passPrefix_)) {
      argv[write++] = argv[i];
      continue;
    }
    Option* option = nullptr;
    std::optional<std::string> value;
    if (arg.starts_with("--")) {
      const size_t eq = arg.find('=');
      const std::string name = arg.substr(0, eq);
      for (const std::unique_ptr<Option>& o : options_) {
        if (o->name_ == name) option = o.get();
      }
      if (option == nullptr) Fail("unknown option '" + name + "'" + Accepted());
      if (eq != std::string::npos) value = arg.substr(eq + 1);
      if (option->takesValue_ && !value) {
        if (i + 1 >= argc) FailMissing(option->name_);
        value = argv[++i];
      }
      if (!option->takesValue_ && value) FailOption(option->name_, *value);
    } else {
      for (size_t k = 0, seen = 0; k < options_.size() && option == nullptr; ++k) {
        if (!options_[k]->name_.starts_with("-") && seen++ == positional) option = options_[k].get();
      }
      if (option == nullptr) {
        Fail((arg.starts_with("-") ? "unknown option '" : "unexpected argument '") + arg + "'" + Accepted());
      }
      ++positional;
      value = arg;
    }
    if (std::optional<std::string> problem = option->set_(*option, value.value_or(""))) {
      FailOption(option->name_, value.value_or(""), *problem);
    }
    option->given_ = true;
  }
  for (const std::unique_ptr<Option>& o : options_) {
    if (o->required_ && !o->given_) FailMissing(o->name_);
  }
  if (passThrough_) {
    argc = write;
    argv[argc] = nullptr;
  }
}

}  // namespace quadrant::cli
