#include "tools/command.h"

#include <gflags/gflags.h>

#include <algorithm>
#include <iostream>

#include "core/error.h"

namespace dala {
namespace {

std::vector<Command>& Registry() {
  static std::vector<Command> commands;
  return commands;
}

void PrintTopLevelHelp(std::ostream& os) {
  os << "dala: vision-based SLAM (stereo and monocular), after Lemaire et al., IJCV 2007.\n\n"
        "usage: dala COMMAND [ARGS] [--flags]\n\ncommands:\n";
  std::vector<Command> commands = Registry();
  std::sort(commands.begin(), commands.end(),
            [](const Command& a, const Command& b) { return a.name < b.name; });
  for (const Command& c : commands) {
    os << "  " << c.name << std::string(c.name.size() < 10 ? 10 - c.name.size() : 1, ' ')
       << c.summary << "\n";
  }
  os << "\n`dala COMMAND --help` describes a command and its flags.\n";
}

void PrintCommandHelp(const Command& command, std::ostream& os) {
  os << "usage: " << command.usage << "\n";
  std::vector<gflags::CommandLineFlagInfo> flags;
  gflags::GetAllFlags(&flags);
  bool header = false;
  for (const auto& f : flags) {
    // gflags stores the file name as given to the compiler; compare by basename. Shared flags
    // (tools/common_flags.cc) are listed when the command's usage mentions them.
    const auto base = [](const std::string& p) { return p.substr(p.find_last_of('/') + 1); };
    const bool own = base(f.filename) == base(command.source_file);
    const bool shared = base(f.filename) == "common_flags.cc" &&
                        command.usage.find("--" + f.name) != std::string::npos;
    if (!own && !shared) continue;
    if (!header) {
      os << "\nflags:\n";
      header = true;
    }
    os << "  --" << f.name << " (" << f.description << ")\n      type: " << f.type
       << "  default: " << (f.type == "string" ? "\"" + f.default_value + "\"" : f.default_value)
       << "\n";
  }
}

}  // namespace

CommandRegistrar::CommandRegistrar(const Command& command) { Registry().push_back(command); }

int RunCli(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h" ||
      std::string(argv[1]) == "help") {
    PrintTopLevelHelp(std::cout);
    return argc < 2 ? 2 : 0;
  }
  const std::string name = argv[1];
  const auto& commands = Registry();
  const auto it = std::find_if(commands.begin(), commands.end(),
                               [&](const Command& c) { return c.name == name; });
  if (it == commands.end()) {
    std::cerr << "dala: unknown command '" << name << "'\n\n";
    PrintTopLevelHelp(std::cerr);
    return 2;
  }
  // Flags after the command name; a --help anywhere prints this command's help.
  std::vector<char*> sub_argv;
  std::string program = std::string("dala ") + name;
  sub_argv.push_back(program.data());
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h" || a == "-help") {
      PrintCommandHelp(*it, std::cout);
      return 0;
    }
    sub_argv.push_back(argv[i]);
  }
  int sub_argc = static_cast<int>(sub_argv.size());
  char** sub_argv_ptr = sub_argv.data();
  gflags::SetUsageMessage(it->usage);
  gflags::ParseCommandLineNonHelpFlags(&sub_argc, &sub_argv_ptr, /*remove_flags=*/true);
  std::vector<std::string> args(sub_argv_ptr + 1, sub_argv_ptr + sub_argc);
  try {
    return it->run(args);
  } catch (const Error& e) {
    std::cerr << "dala " << name << ": error: " << e.what() << "\n";
    return 2;
  }
}

}  // namespace dala
