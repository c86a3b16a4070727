// The benchmark programs' command line (issue #28 item 5, issue 16's rules): each program declares
// its options once, with the value each takes, its help text and its default, and one parser reads
// argv for all of them.
//
//   quadrant::cli::Parser p("quadrant_effects", "What each effect of the scene API costs Quadrant.");
//   p.String("--out", &args.out, "DIR", "output directory");
//   p.Int("--steps", &args.steps, 1, 1000000, "timed steps").Default("120 (20 with --quick)");
//   p.Flag("--quick", &args.quick, "a small, fast run");
//   p.Parse(argc, argv);
//
// The target's value at declaration is the default (help prints it unless Default() says
// otherwise); a given option overwrites it. Options are `--name VALUE` or `--name=VALUE`; a name
// without the leading "--" is a positional argument, taken in declaration order.
//
// A bad command line is exactly one line on stderr and exit status 2, nothing on stdout:
//   <program>: --option: <what it accepts> (got '<value>')
//   <program>: --option: unknown case 'x'; <what it accepts> (got 'a,x')   (a list's bad item)
//   <program>: --option: <what it accepts> (got nothing)     (no value, or a required one missing)
//   <program>: unknown option '--frob' (accepted: --out, --steps, ...)
// `--help` (or `-h`) prints the program's own options on stdout and exits 0. With PassThrough
// (programs on Google Benchmark), arguments with the given prefix stay in argv for the next parser,
// and `--help` prints this program's options and stays too, so that Google Benchmark adds its own.
#pragma once

#include <concepts>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace quadrant::cli {

/// A check of one item of a name or name-list option: empty when accepted, else the problem
/// ("unknown engine 'x' ..."), which the error line puts before what the option accepts.
using ItemCheck = std::function<std::string(const std::string& item)>;

/// One declared option (Parser's declarations return it for the modifiers below).
class Option {
 public:
  /// The default as help shows it, where the target's initial value is not it ("600; 120 with
  /// --quick"); "" shows none.
  Option& Default(std::string text);
  /// What the option accepts, in help and in the error line (each kind has its own otherwise).
  Option& Accepts(std::string text);
  /// The value's name in help (DIR, N, a,b).
  Option& Value(std::string text);
  /// An extra check of every item of a name or name-list option.
  Option& Check(ItemCheck check);
  /// Name lists: the word `none` is the empty list (and an empty list is accepted only so); adds
  /// ", or none" to what it accepts (so it goes after Accepts()).
  Option& AllowNone();
  /// Must be given (a positional argument, or an option the program cannot run without).
  Option& Required();

 private:
  friend class Parser;
  std::string name_, help_, value_, accepts_, default_;
  bool takesValue_ = true, required_ = false, allowNone_ = false, given_ = false;
  ItemCheck check_;
  // Reads the option's text into the target: nothing when accepted, else the problem ("" when
  // what it accepts says it all).
  std::function<std::optional<std::string>(const Option& self, const std::string& text)> set_;
};

class Parser {
 public:
  /// `program` starts every line it prints; `summary` is help's first paragraph.
  Parser(std::string program, std::string summary);

  /// A flag: no value; given, it sets *target to true.
  Option& Flag(std::string name, bool* target, std::string help);
  /// A whole decimal number in [least, most].
  template <std::integral T>
  Option& Int(std::string name, T* target, long long least, long long most, std::string help) {
    Option& o = Add(std::move(name), std::move(help), "N", IntAccepts(least, most), std::to_string(*target));
    o.set_ = [target, least, most](const Option&, const std::string& text) -> std::optional<std::string> {
      long long v = 0;
      if (!ParseInteger(text, least, most, v)) return "";
      *target = static_cast<T>(v);
      return std::nullopt;
    };
    return o;
  }
  /// A finite decimal number in [least, most].
  Option& Double(std::string name, double* target, double least, double most, std::string help);
  /// A comma-separated list of integers in [least, most], no empty item.
  Option& IntList(std::string name, std::vector<int>* target, int least, int most, std::string help);
  /// Any text (a file, a directory).
  Option& String(std::string name, std::string* target, std::string value, std::string help);
  /// A directory the program writes into: one that exists, or a path where one can be created
  /// (its nearest existing ancestor is a directory). Checked before the program runs, so a run
  /// is not lost to an output path that cannot hold it. Nothing is created here.
  Option& OutputDirectory(std::string name, std::string* target, std::string help);
  /// One name of `allowed` ("unknown <noun> 'x'" otherwise); an empty `allowed` takes any name
  /// that passes Check().
  Option& Name(std::string name, std::string* target, std::vector<std::string> allowed, std::string noun,
               std::string help);
  /// A comma-separated list of names of `allowed`, no empty item, as Name.
  Option& NameList(std::string name, std::vector<std::string>* target, std::vector<std::string> allowed,
                   std::string noun, std::string help);

  /// Arguments that start with `prefix` (e.g. "--benchmark_") are left in argv, in order, for
  /// another parser; so is --help, after this program's help and `epilogue` are printed.
  void PassThrough(std::string prefix, std::string epilogue);
  /// Text printed after the options in help.
  void Epilogue(std::string text);
  /// Whether this process prints (one rank of an MPI job prints, every rank exits alike).
  void Quiet(bool quiet);
  /// Called instead of std::exit (an MPI program finalises first); must not return.
  void OnExit(std::function<void(int status)> exit);

  /// Reads argv (removing what it took when PassThrough is set). A bad command line exits 2,
  /// --help exits 0 (without PassThrough).
  void Parse(int& argc, char** argv);
  /// Whether the option was on the command line.
  bool Given(std::string_view name) const;
  /// One line "<program>: <problem>" on stderr, exit 2: for what the program checks itself.
  [[noreturn]] void Fail(const std::string& problem) const;
  /// The option's one error line for `value` (with `problem` before what it accepts), exit 2.
  [[noreturn]] void FailOption(std::string_view name, const std::string& value, const std::string& problem = "") const;
  /// The option's one error line when it is missing or has no value ("(got nothing)"), exit 2.
  [[noreturn]] void FailMissing(std::string_view name) const;
  /// After benchmark::Initialize took the flags it knows from argv: anything left (an unknown
  /// --benchmark_* flag, or one whose value it refused) is refused in one line, exit 2 (Google
  /// Benchmark's own message names the binary's path).
  void FailOnRest(int argc, char** argv) const;
  /// The program's help: usage, summary, every option with its value, help, accepts and default.
  void PrintHelp(std::FILE* out) const;

 private:
  Option& Add(std::string name, std::string help, std::string value, std::string accepts, std::string def);
  Option& Find(std::string_view name) const;
  [[noreturn]] void Exit(int status) const;
  std::string Accepted() const;  // " (accepted: ...)" for an unknown option
  static std::string IntAccepts(long long least, long long most);
  static bool ParseInteger(const std::string& text, long long least, long long most, long long& out);

  std::string program_, summary_, epilogue_, passPrefix_;
  bool passThrough_ = false, quiet_ = false;
  std::function<void(int)> exit_;
  std::vector<std::unique_ptr<Option>> options_;  // pointers: the Option& handed out stay valid
};

}  // namespace quadrant::cli
