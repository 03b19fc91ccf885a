// fullarm: the one command-line program (cli.hpp; exit codes in exit_codes.hpp and docs/cli.md).

#include <iostream>
#include <string>
#include <vector>

#include "cli.hpp"

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  return fullarm::app::runFullarm(args, std::cout, std::cerr);
}
