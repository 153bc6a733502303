#include "cli_test_util.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "test_paths.hpp"

namespace dynamap::test {
namespace fs = std::filesystem;

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::size_t countDataLines(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::size_t n = 0;
  while (std::getline(in, line)) n += (!line.empty() && line[0] != '#') ? 1 : 0;
  return n;
}

CommandResult runDynamap(const std::vector<std::string>& args, double interrupt_after_s) {
  static int counter = 0;
  const fs::path dir = fs::temp_directory_path() / ("dynamap_cli_" + std::to_string(getpid()) +
                                                    "_" + std::to_string(counter++));
  fs::create_directories(dir);
  const std::string out_path = (dir / "stdout").string();
  const std::string err_path = (dir / "stderr").string();
  const std::string exe = (binaryDir() / "bin" / "dynamap").string();

  const pid_t pid = fork();
  if (pid == 0) {
    const int out_fd = open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err_fd = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(out_fd, STDOUT_FILENO);
    dup2(err_fd, STDERR_FILENO);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(exe.c_str()));
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(exe.c_str(), argv.data());
    _exit(127);
  }
  if (interrupt_after_s > 0.0) {
    std::this_thread::sleep_for(std::chrono::duration<double>(interrupt_after_s));
    kill(pid, SIGINT);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = readFile(out_path);
  result.err = readFile(err_path);
  fs::remove_all(dir);
  return result;
}

std::string makeTeddySubset(const std::string& name, std::size_t frames,
                            const std::string& source) {
  const fs::path src = sharedData() / source;
  const fs::path dir = freshTempDir(name);
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  for (const char* list : {"rgb.txt", "depth.txt"}) {
    std::ifstream in(src / list);
    std::ofstream out(dir / list);
    std::string line;
    std::size_t n = 0;
    while (std::getline(in, line) && n < frames) {
      out << line << "\n";
      if (line.empty() || line[0] == '#') continue;
      ++n;
      const std::string file = line.substr(line.find(' ') + 1);
      fs::create_symlink(src / file, dir / file);
    }
  }
  fs::copy_file(src / "groundtruth.txt", dir / "groundtruth.txt");
  return dir.string();
}

}  // namespace dynamap::test
