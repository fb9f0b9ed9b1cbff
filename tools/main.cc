// The `dala` command line. Subcommands register themselves (see tools/command.h).
#include <glog/logging.h>

#include "tools/command.h"

int main(int argc, char** argv) {
  google::InitGoogleLogging(argv[0]);
  FLAGS_logtostderr = true;
  return dala::RunCli(argc, argv);
}
