// strata: the engine's command-line front end. See docs/commands.md for the commands and their outputs, and the
// README's "Exit codes" for the contract every subcommand keeps (apps/cli_support.h).
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <new>
#include <iostream>
#include <string>
#include <vector>

#include "apps/cli_support.h"
#include "apps/commands.h"

#ifndef STRATA_VERSION
#define STRATA_VERSION "unknown"
#endif

namespace {

using strata::cli::kExitOk;
using strata::cli::kExitUsage;
using strata::cli::print_error;

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

std::string names_of(const CLI::App& app) {
  std::string out;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    out += (out.empty() ? "" : ", ") + sub->get_name();
  return out;
}

// "unknown command 'crwod' (did you mean 'crowd'? commands: ...)": the nearest name by edit distance, or a
// prefix match, offered only when it is close enough to be a plausible slip.
std::string unknown_subcommand(const CLI::App& parent, const std::string& word) {
  if (parent.get_subcommands([](const CLI::App*) { return true; }).empty())
    return "'" + parent.get_name() + "' has no subcommand '" + word + "'";
  std::string best;
  std::size_t best_distance = 0;
  for (const CLI::App* sub : parent.get_subcommands([](const CLI::App*) { return true; })) {
    const std::string& name = sub->get_name();
    std::size_t d = edit_distance(word, name);
    if (name.rfind(word, 0) == 0 || word.rfind(name, 0) == 0) d = std::min<std::size_t>(d, 1);
    if (best.empty() || d < best_distance) best = name, best_distance = d;
  }
  std::string text = "unknown command '" + word + "'";
  if (!best.empty() && best_distance <= std::max<std::size_t>(2, word.size() / 3))
    text += " (did you mean '" + best + "'?";
  else
    text += " (";
  text += (text.back() == '(' ? "" : " ") + std::string("commands: ") + names_of(parent) + ")";
  return text;
}

// The chain of subcommands named on the command line ("report gait"), and the app that chain ends at; the first
// word that is not an option and not a subcommand of where it stands is returned in `unknown`. Options that take
// values come after the subcommand names in every strata command, so the words up to the first option are the
// chain.
const CLI::App* resolve_chain(const CLI::App& app, int argc, char** argv, std::string& chain, std::string& unknown) {
  const CLI::App* at = &app;
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word[0] == '-') break;
    if (at->get_subcommands([](const CLI::App*) { return true; }).empty()) break;  // a positional (info FILE)
    const CLI::App* next = nullptr;
    try {
      next = at->get_subcommand(word);
    } catch (const CLI::OptionNotFound&) {
      unknown = word;
      return at;
    }
    chain += (chain.empty() ? "" : " ") + word;
    at = next;
  }
  return at;
}

// The help of `at` alone, its usage line starting with `name` ("strata report gait"). App::help() was rejected: called while a subcommand is selected (as `help` itself is)
// it prints that subcommand's help instead.
std::string help_of(const CLI::App& at, const std::string& prefix) {
  return at.get_formatter()->make_help(&at, prefix, CLI::AppFormatMode::Normal);
}

// Joins TBB's worker threads before main returns. Otherwise they are still alive, or being torn down by TBB's
// static destructors, while LeakSanitizer's exit-time check runs; its stop-the-world tracer then crashes now and
// again ("Tracer caught signal 11", google/sanitizers#1353) and turns a passing run into exit 1 (seen once in CI).
// With the workers joined, the tracer finds fewer threads to stop; outside sanitizer builds it costs one join.
// A ctest retry of failed tests was the alternative, rejected: it doubles the cost of every real failure and
// hides a real intermittent one.
struct JoinTbbWorkersAtExit {
  tbb::task_scheduler_handle handle{tbb::attach{}};
  ~JoinTbbWorkersAtExit() { (void)tbb::finalize(handle, std::nothrow); }
};

}  // namespace

int main(int argc, char** argv) {
  JoinTbbWorkersAtExit join_tbb_workers;
  CLI::App app{"Strata: animate and render crowds of layered H-Anim humanoids"};
  app.name("strata");
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("strata ") + STRATA_VERSION, "Print the version and exit");
  int exit_code = kExitOk;
  strata::cli::add_info_command(app, exit_code);
  strata::cli::add_crowd_command(app, exit_code);
  strata::cli::add_view_command(app, exit_code);
  strata::cli::add_report_command(app, exit_code);
  strata::cli::add_bench_command(app, exit_code);
  strata::cli::add_export_command(app, exit_code);
  strata::cli::add_soak_command(app, exit_code);

  // `strata help [COMMAND [SUBCOMMAND]]`: the help of what it names, as `--help` would print it.
  auto* help = app.add_subcommand("help", "Show the help of a command: strata help [COMMAND [SUBCOMMAND]]");
  auto help_words = std::make_shared<std::vector<std::string>>();
  help->add_option("COMMAND", *help_words, "Command (and subcommand) to describe");
  help->callback([&app, help_words, &exit_code] {
    const CLI::App* at = &app;
    std::string chain;
    for (const std::string& word : *help_words) {
      try {
        at = at->get_subcommand(word);
        chain += (chain.empty() ? "" : " ") + word;
      } catch (const CLI::OptionNotFound&) {
        print_error("help", unknown_subcommand(*at, word));
        exit_code = kExitUsage;
        return;
      }
    }
    std::cout << help_of(*at, chain.empty() ? "strata" : "strata " + chain);
  });

  std::string chain, unknown;
  const CLI::App* target = resolve_chain(app, argc, argv, chain, unknown);
  if (!unknown.empty()) {
    print_error(chain, unknown_subcommand(*target, unknown));
    return kExitUsage;
  }
  if (argc < 2) {
    print_error("", "a command is required (" + names_of(app) + "); see strata help");
    return kExitUsage;
  }

  // Under mpirun only `strata crowd`, `strata bench` and `strata report crowd` spread their crowd over the
  // processes; any other command would run whole in each of them, writing the same outputs K times.
  if (strata::cli::launcher_size() > 1 && !chain.empty() && chain.rfind("crowd", 0) != 0 &&
      chain.rfind("bench", 0) != 0 && chain != "report crowd" && chain.rfind("help", 0) != 0) {
    print_error(chain, "runs in one process; under mpirun only `strata crowd`, `strata bench` and `strata report "
                       "crowd` spread a crowd over the processes (docs/scale-out.md)");
    return kExitUsage;
  }
  strata::cli::install_interrupt_handlers();
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::cout << help_of(*target, chain.empty() ? "strata" : "strata " + chain);
    return kExitOk;
  } catch (const CLI::CallForAllHelp&) {
    std::cout << app.help("", CLI::AppFormatMode::All);
    return kExitOk;
  } catch (const CLI::CallForVersion& e) {
    std::cout << e.what() << "\n";
    return kExitOk;
  } catch (const CLI::ParseError& e) {
    // Every parser failure is a usage error (2): CLI11's own codes (105 ConversionError, 106 ValidationError,
    // 109 ExtrasError, ...) would make a script's check depend on which check tripped.
    std::string message = e.what();
    if (message == "A subcommand is required")
      message = "a subcommand is required (" + names_of(*target) + ")";
    print_error(chain, message + "; see strata help" + (chain.empty() ? "" : " " + chain));
    return kExitUsage;
  } catch (const std::exception& e) {
    // A callback that let an exception out: still one line and exit 1, never a stack trace or an abort.
    print_error(chain, strata::cli::error_text(e));
    return strata::cli::kExitFailure;
  }
  return exit_code;
}
