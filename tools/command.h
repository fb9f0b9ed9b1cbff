#ifndef DALA_TOOLS_COMMAND_H_
#define DALA_TOOLS_COMMAND_H_

// The `dala` CLI is one binary with subcommands (`dala synth`, `dala eval`, ...). Each
// subcommand lives in its own cmd_<name>.cc, defines its gflags there, and registers itself:
//
//   static dala::CommandRegistrar registrar({"eval", "compare a trajectory with ground truth",
//       "dala eval GT EST [--align se3|sim3|none] ...", &RunEval, __FILE__});
//
// `Run` gets the positional arguments (flags already parsed by gflags) and returns the exit
// status. A dala::Error escaping Run is printed by main and gives exit status 2.

#include <string>
#include <vector>

namespace dala {

struct Command {
  std::string name;
  std::string summary;  // One line for `dala --help`.
  std::string usage;    // Full usage text for `dala NAME --help` (flags are listed after it).
  int (*run)(const std::vector<std::string>& args);
  std::string source_file;  // __FILE__: its flags are the ones defined in this file.
};

class CommandRegistrar {
 public:
  explicit CommandRegistrar(const Command& command);
};

// Runs the CLI; used by main() and by tests that call the CLI in-process.
int RunCli(int argc, char** argv);

}  // namespace dala

#endif  // DALA_TOOLS_COMMAND_H_
