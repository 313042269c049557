#include "pil_client.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

namespace sim {

RxResult parse_actuator_bytes(pil::Parser& parser, const std::uint8_t* bytes, int len, int& pos,
                              pil::ActuatorFrame& f, std::string& err) {
  while (pos < len) {
    switch (parser.feed(bytes[pos++])) {
      case pil::Parser::kPending:
        break;
      case pil::Parser::kFrame:
        if (!parser.decode(f)) return err = "unexpected frame type from the firmware", RxResult::kError;
        return RxResult::kFrame;
      case pil::Parser::kBadChecksum:
        return err = "corrupted actuator frame (checksum mismatch)", RxResult::kError;
      case pil::Parser::kBadHeader:
        return err = "corrupted actuator frame (bad header)", RxResult::kError;
    }
  }
  return RxResult::kNeedMore;
}

PilClient::~PilClient() { stop(); }

std::vector<std::string> PilClient::qemu_command(const std::string& qemu, const std::string& elf) {
  // UART0 of the board is the first -serial: here the process's stdin/stdout. -icount shift=0:
  // one instruction = 1 ns of virtual time, so the firmware's timing is an instruction count.
  return {qemu,      "-M",           "mps2-an386",
          "-display", "none",        "-monitor",
          "none",     "-serial",     "stdio",
          "-semihosting-config",     "enable=on,target=native",
          "-icount",  "shift=0",     "-no-reboot",
          "-kernel",  elf};
}

bool PilClient::start(const std::vector<std::string>& argv, std::string& err, double ready_timeout_s) {
  int in[2], out[2];
  if (pipe(in) != 0 || pipe(out) != 0) return err = std::string("pipe: ") + std::strerror(errno), false;
  const pid_t pid = fork();
  if (pid < 0) return err = std::string("fork: ") + std::strerror(errno), false;
  if (pid == 0) {
    dup2(in[0], STDIN_FILENO);
    dup2(out[1], STDOUT_FILENO);
    close(in[0]);
    close(in[1]);
    close(out[0]);
    close(out[1]);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execvp(args[0], args.data());
    std::fprintf(stderr, "pil: cannot start %s: %s\n", args[0], std::strerror(errno));
    _exit(127);
  }
  close(in[0]);
  close(out[1]);
  to_child_ = in[1];
  from_child_ = out[0];
  pid_ = pid;
  signal(SIGPIPE, SIG_IGN);  // a dead peer is an error return, not a signal
  parser_.reset();
  rx_len_ = rx_pos_ = 0;
  pil::ActuatorFrame hello;
  if (!receive(hello, ready_timeout_s, err)) return err = "firmware not ready: " + err, false;
  if (hello.seq != pil::kHelloSeq) return err = "firmware did not start with its hello frame", false;
  return true;
}

bool PilClient::send_raw(const std::uint8_t* p, int n, std::string& err) {
  while (n > 0) {
    const ssize_t w = write(to_child_, p, static_cast<size_t>(n));
    if (w < 0) {
      if (errno == EINTR) continue;
      return err = std::string("link write failed (firmware gone?): ") + std::strerror(errno), false;
    }
    p += w;
    n -= static_cast<int>(w);
  }
  return true;
}

bool PilClient::send(const pil::SensorFrame& f, std::string& err) {
  std::uint8_t buf[pil::kMaxFrame];
  return send_raw(buf, pil::encode(f, buf), err);
}

bool PilClient::receive(pil::ActuatorFrame& f, double timeout_s, std::string& err) {
  using clock = std::chrono::steady_clock;
  const auto deadline = clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    // Parse what has arrived; bytes after a complete frame stay buffered for the next call.
    switch (parse_actuator_bytes(parser_, rx_, rx_len_, rx_pos_, f, err)) {
      case RxResult::kFrame:
        return true;
      case RxResult::kError:
        return false;
      case RxResult::kNeedMore:
        break;
    }
    const double left = std::chrono::duration<double>(deadline - clock::now()).count();
    if (left <= 0) {
      return err = std::string("no actuator frame from the firmware within ") + std::to_string(timeout_s) + " s" +
                   (parser_.in_frame() ? " (a frame started but did not complete: short frame)" : ""),
             false;
    }
    pollfd p{from_child_, POLLIN, 0};
    const int r = poll(&p, 1, static_cast<int>(left * 1000) + 1);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) return err = std::string("poll: ") + std::strerror(errno), false;
    if (r == 0) continue;
    const ssize_t n = read(from_child_, rx_, sizeof rx_);
    if (n == 0) return err = "the firmware closed the link (exited)", false;
    if (n < 0) {
      if (errno == EINTR) continue;
      return err = std::string("link read failed: ") + std::strerror(errno), false;
    }
    rx_len_ = static_cast<int>(n);
    rx_pos_ = 0;
  }
}

int PilClient::stop() {
  if (pid_ <= 0) return -1;
  if (to_child_ >= 0) close(to_child_);
  to_child_ = -1;
  int status = 0;
  // Give the peer a moment to exit on its own (end of input), then kill it.
  for (int i = 0; i < 20; ++i) {
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      close(from_child_);
      from_child_ = -1;
      return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    usleep(10000);
  }
  kill(pid_, SIGKILL);
  waitpid(pid_, &status, 0);
  pid_ = -1;
  close(from_child_);
  from_child_ = -1;
  return -1;
}

}  // namespace sim
