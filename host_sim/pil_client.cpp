#include "pil_client.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <thread>

#include "osc/runtime/io.hpp"

namespace sim {

RxResult parse_firmware_bytes(pil::Parser& parser, const std::uint8_t* bytes, int len, int& pos, FirmwareFrame& f,
                              pil::LinkCounters& counters, std::string& err) {
  // The events of the bytes already fed first (parser.next()), then the next byte.
  for (;;) {
    pil::Parser::Result r = parser.next();
    if (r == pil::Parser::kPending) {
      if (pos >= len) break;
      r = parser.feed(bytes[pos++]);
    }
    switch (r) {
      case pil::Parser::kPending:
        break;
      case pil::Parser::kJunk:
        counters[pil::kErrJunk] += static_cast<std::uint32_t>(parser.junk());
        break;
      case pil::Parser::kFrame:
        f.type = parser.type();
        if (parser.decode(f.actuator) || parser.decode(f.answer) || parser.decode(f.state) || parser.decode(f.trace) ||
            parser.decode(f.param_answer) || parser.decode(f.capture_data) || parser.decode(f.identify) ||
            parser.decode(f.identify_offset) || parser.decode(f.identify_payload))
          return RxResult::kFrame;
        ++counters[pil::kErrHeader];  // a type the host sends
        return err = "unexpected frame type from the firmware", RxResult::kError;
      case pil::Parser::kBadChecksum:
      case pil::Parser::kBadHeader:
      case pil::Parser::kBadLength:
      case pil::Parser::kShortFrame:
        ++counters[pil::Parser::error_of(r)];
        return err = r == pil::Parser::kBadChecksum ? "corrupted actuator frame (checksum mismatch)"
                     : r == pil::Parser::kBadHeader ? "corrupted actuator frame (bad header: unknown type)"
                     : r == pil::Parser::kBadLength ? "corrupted actuator frame (bad header: wrong length)"
                                                    : "actuator frame cut short",
               RxResult::kError;
    }
  }
  return RxResult::kNeedMore;
}

namespace {
void file_reply(const FirmwareFrame& f, PilReplies& replies) {
  if (f.type == pil::kAnswerFrame) replies.answers.push_back(f.answer);
  if (f.type == pil::kStateFrame) replies.states.push_back(f.state);
  if (f.type == pil::kTraceFrame) replies.traces.push_back(f.trace);
  if (f.type == pil::kParamAnswerFrame) replies.params.push_back(f.param_answer);
  if (f.type == pil::kCaptureDataFrame) replies.captures.push_back(f.capture_data);
  if (f.type == pil::kIdentifyFrame) replies.identifies.push_back(f.identify);
  if (f.type == pil::kIdentifyOffsetFrame) replies.identify_offsets.push_back(f.identify_offset);
  if (f.type == pil::kIdentifyPayloadFrame) replies.identify_payloads.push_back(f.identify_payload);
}
}  // namespace

RxResult parse_actuator_bytes(pil::Parser& parser, const std::uint8_t* bytes, int len, int& pos, pil::ActuatorFrame& f,
                              pil::LinkCounters& counters, std::string& err, PilReplies* replies) {
  FirmwareFrame ff;
  for (;;) {
    const RxResult r = parse_firmware_bytes(parser, bytes, len, pos, ff, counters, err);
    if (r != RxResult::kFrame) return r;
    if (ff.type == pil::kActuatorFrame) {
      f = ff.actuator;
      return r;
    }
    if (replies) file_reply(ff, *replies);
  }
}

PilClient::~PilClient() { stop(); }

const char* name(PilLink link) { return link == PilLink::kUart ? "uart" : "semihosting"; }

bool parse_pil_link(const std::string& text, PilLink& link) {
  if (text == "uart")
    link = PilLink::kUart;
  else if (text == "semihosting")
    link = PilLink::kSemihosting;
  else
    return false;
  return true;
}

namespace {

std::uint32_t le32(const std::string& b, std::size_t at) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(b[at])) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 1])) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 2])) << 16 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 3])) << 24;
}
std::uint32_t le16(const std::string& b, std::size_t at) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(b[at])) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 1])) << 8;
}

/// Tag_CPU_arch of the "aeabi" file attributes in an .ARM.attributes section (ARM IHI 0045), or -1.
/// Tags 4, 5, 65, 67 and odd tags from 32 on are NUL-terminated strings; the rest are ULEB128,
/// except Tag_compatibility (32: a ULEB128, then a string).
int cpu_arch(const std::string& a) {
  if (a.empty() || a[0] != 'A') return -1;
  std::size_t pos = 1;
  while (pos + 4 <= a.size()) {
    const std::size_t len = le32(a, pos);
    if (len < 4 || pos + len > a.size()) return -1;
    const std::size_t end = pos + len;
    std::size_t p = pos + 4;
    const std::size_t vendor_end = a.find('\0', p);
    if (vendor_end == std::string::npos || vendor_end >= end) return -1;
    const bool aeabi = a.compare(p, vendor_end - p, "aeabi") == 0;
    p = vendor_end + 1;
    while (aeabi && p + 5 <= end) {
      const int kind = static_cast<unsigned char>(a[p]);
      const std::size_t sub_len = le32(a, p + 1);
      if (sub_len < 5 || p + sub_len > end) return -1;
      const std::size_t sub_end = p + sub_len;
      std::size_t q = p + 5;
      auto uleb = [&](std::uint64_t& v) {
        v = 0;
        for (int shift = 0; q < sub_end && shift < 64; shift += 7) {
          const auto byte = static_cast<unsigned char>(a[q++]);
          v |= static_cast<std::uint64_t>(byte & 0x7F) << shift;
          if ((byte & 0x80) == 0) return true;
        }
        return false;
      };
      auto skip_string = [&] {
        const std::size_t z = a.find('\0', q);
        if (z == std::string::npos || z >= sub_end) return false;
        q = z + 1;
        return true;
      };
      while (kind == 1 && q < sub_end) {  // Tag_File: the attributes of the whole file
        std::uint64_t tag = 0, value = 0;
        if (!uleb(tag)) return -1;
        if (tag == 4 || tag == 5 || tag == 65 || tag == 67 || (tag > 32 && tag % 2 == 1)) {
          if (!skip_string()) return -1;
        } else if (tag == 32) {
          if (!uleb(value) || !skip_string()) return -1;
        } else {
          if (!uleb(value)) return -1;
          if (tag == 6) return static_cast<int>(value);
        }
      }
      p = sub_end;
    }
    pos = end;
  }
  return -1;
}

}  // namespace

std::string qemu_machine(const std::string& elf, std::string& err) {
  std::ifstream f(elf, std::ios::binary);
  if (!f) return err = "cannot read firmware image " + elf, "";
  std::string b((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (b.size() < 52 || b.compare(0, 4,
                                 "\x7F"
                                 "ELF") != 0)
    return err = "firmware image " + elf + " is not an ELF file", "";
  if (b[4] != 1 || b[5] != 1 || le16(b, 18) != 40)
    return err = "firmware image " + elf + " is not a 32-bit little-endian ARM ELF file", "";
  const std::size_t shoff = le32(b, 0x20), shentsize = le16(b, 0x2E), shnum = le16(b, 0x30);
  int arch = -1;
  for (std::size_t i = 0; i < shnum && shentsize >= 40; ++i) {
    const std::size_t h = shoff + i * shentsize;
    if (h + 40 > b.size()) break;
    if (le32(b, h + 4) != 0x70000003u) continue;  // SHT_ARM_ATTRIBUTES
    const std::size_t off = le32(b, h + 16), size = le32(b, h + 20);
    if (off > b.size() || size > b.size() - off) break;
    arch = cpu_arch(b.substr(off, size));
    break;
  }
  if (arch == 10) return "mps2-an385";  // ARMv7 (with the M profile: ARMv7-M, the Cortex-M3)
  if (arch == 13) return "mps2-an386";  // ARMv7E-M (Cortex-M4F)
  return err = "firmware image " + elf +
               (arch < 0 ? " names no ARM architecture (no build attributes)"
                         : " is for ARM architecture " + std::to_string(arch) +
                               ", not ARMv7-M or ARMv7E-M (no MPS2 machine here)"),
         "";
}

std::vector<std::string> PilClient::qemu_command(const std::string& qemu, const std::string& elf, PilLink link,
                                                 std::string& err) {
  const std::string machine = qemu_machine(elf, err);
  if (machine.empty()) return {};
  // -icount shift=0: one instruction = 1 ns of virtual time, so the firmware's timing is an
  // instruction count. The link is the process's stdin/stdout: UART0 (the first -serial), or the
  // semihosting console.
  std::vector<std::string> argv = {qemu, "-M", machine, "-display", "none", "-monitor", "none"};
  if (link == PilLink::kUart) {
    argv.insert(argv.end(), {"-serial", "stdio", "-semihosting-config", "enable=on,target=native"});
  } else {
    // The image's semihosting command line (arg=) asks it for the console transport.
    argv.insert(argv.end(), {"-serial", "null", "-semihosting-config", "enable=on,target=native,arg=link=semihosting"});
  }
  argv.insert(argv.end(), {"-icount", "shift=0", "-no-reboot", "-kernel", elf});
  return argv;
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
  reaped_ = false;
  signal(SIGPIPE, SIG_IGN);  // a dead peer is an error return, not a signal
  parser_.reset();
  rx_len_ = rx_pos_ = 0;
  replies_.clear();
  sensor_sent_ = traced_ = false;
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

template <class F>
bool PilClient::send_frame(const F& f, std::string& err) {
  std::uint8_t buf[pil::kMaxFrame];
  return send_raw(buf, pil::encode(f, buf), err);
}

bool PilClient::send(const pil::SensorFrame& f, std::string& err) {
  if (!sensor_sent_) traced_ = (f.inject & pil::kConfigTrace) != 0;  // the first one configures the session
  sensor_sent_ = true;
  return send_frame(f, err);
}
bool PilClient::send(const pil::CommandFrame& f, std::string& err) { return send_frame(f, err); }
bool PilClient::send(const pil::SetpointFrame& f, std::string& err) { return send_frame(f, err); }
bool PilClient::send(const pil::SetpointVelocityFrame& f, std::string& err) { return send_frame(f, err); }
bool PilClient::send(const pil::ParamFrame& f, std::string& err) { return send_frame(f, err); }
bool PilClient::send(const pil::CaptureFrame& f, std::string& err) { return send_frame(f, err); }

bool PilClient::receive(pil::ActuatorFrame& f, double timeout_s, std::string& err) {
  computed_s_ = 0;
  computing_cap_s_ = kComputingWaits * timeout_s;
  return receive_actuator(f, timeout_s, err) == Rx::kFrame;
}

namespace {
/// The CPU time a process has used, user and system [s] (/proc/PID/stat's fields 14 and 15), or -1.
double process_cpu_seconds(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (pid <= 0 || !std::getline(in, line)) return -1;
  const std::size_t name_end = line.rfind(')');  // the command's name may hold spaces
  if (name_end == std::string::npos) return -1;
  std::istringstream fields(line.substr(name_end + 1));
  std::string skip;
  for (int field = 3; field < 14; ++field) fields >> skip;
  double user = 0, system = 0;
  if (!(fields >> user >> system)) return -1;
  return (user + system) / static_cast<double>(sysconf(_SC_CLK_TCK));
}
}  // namespace

PilClient::CpuMark PilClient::cpu_mark() const {
  return {std::chrono::steady_clock::now(), reaped_ ? -1.0 : process_cpu_seconds(pid_)};
}

bool PilClient::peer_computing(CpuMark& m) {
  const CpuMark now = cpu_mark();
  const double waited = std::chrono::duration<double>(now.at - m.at).count(), used = now.cpu_s - m.cpu_s;
  const bool computing = m.cpu_s >= 0 && now.cpu_s >= 0 && waited > 0.05 && used >= 0.1 * waited;
  m = now;
  if (!computing || computed_s_ + kComputingWait > computing_cap_s_) return false;
  computed_s_ += kComputingWait;
  return true;
}

void PilClient::keep(const FirmwareFrame& f) { file_reply(f, replies_); }

PilClient::Rx PilClient::receive_actuator(pil::ActuatorFrame& f, double timeout_s, std::string& err) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  const double computed_before = computed_s_;
  for (;;) {
    FirmwareFrame ff;
    const double left =
        std::chrono::duration<double>(deadline - Clock::now()).count() + (computed_s_ - computed_before);
    const Rx r = receive_frame(ff, std::max(left, 0.0), err);
    if (r != Rx::kFrame) return r;
    if (ff.type == pil::kActuatorFrame) {
      f = ff.actuator;
      return r;
    }
    keep(ff);
  }
}

PilClient::Rx PilClient::receive_frame(FirmwareFrame& f, double timeout_s, std::string& err) {
  using Clock = std::chrono::steady_clock;
  auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  CpuMark mark = cpu_mark();
  for (;;) {
    // Parse what has arrived; bytes after a complete frame stay buffered for the next call.
    switch (parse_firmware_bytes(parser_, rx_, rx_len_, rx_pos_, f, counters_, err)) {
      case RxResult::kFrame:
        return Rx::kFrame;
      case RxResult::kError:
        return Rx::kCorrupt;
      case RxResult::kNeedMore:
        break;
    }
    const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
    if (left <= 0 && peer_computing(mark)) {
      deadline += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kComputingWait));
      continue;
    }
    if (left <= 0) {
      const bool short_frame = parser_.in_frame();
      ++counters_[short_frame ? pil::kErrShortFrame : pil::kErrSilence];
      return err = std::string("no actuator frame from the firmware within ") + std::to_string(timeout_s) + " s" +
                   (short_frame ? " (a frame started but did not complete: short frame)" : "") +
                   (computed_s_ > 0 ? " after " + std::to_string(computed_s_) + " s more while it computed" : ""),
             Rx::kSilent;
    }
    pollfd p{from_child_, POLLIN, 0};
    const int r = poll(&p, 1, static_cast<int>(left * 1000) + 1);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) return err = std::string("poll: ") + std::strerror(errno), Rx::kGone;
    if (r == 0) continue;
    const ssize_t n = read(from_child_, rx_, sizeof rx_);
    if (n == 0) return err = "the firmware closed the link (" + exit_description() + ")", Rx::kGone;
    if (n < 0) {
      if (errno == EINTR) continue;
      return err = std::string("link read failed: ") + std::strerror(errno), Rx::kGone;
    }
    rx_len_ = static_cast<int>(n);
    rx_pos_ = 0;
  }
}

bool PilClient::codes_in_range(const pil::ActuatorFrame& a) {
  for (std::int32_t c : a.codes)
    if (c < -osc::kDacMaxCode || c > osc::kDacMaxCode) return false;
  return true;
}

PilClient::Exchange PilClient::exchange(const pil::SensorFrame& s, pil::ActuatorFrame& a, double timeout_s,
                                        std::string& err) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  computed_s_ = 0;
  computing_cap_s_ = kComputingWaits * timeout_s;
  const auto left_s = [&] { return std::chrono::duration<double>(deadline - Clock::now()).count() + computed_s_; };
  Exchange x = Exchange::kLost;
  if (send(s, err)) {
    for (;;) {
      pil::ActuatorFrame f;
      const double left = left_s();
      const Rx r = receive_actuator(f, std::max(left, 0.0), err);
      if (r != Rx::kFrame) {
        x = r == Rx::kCorrupt ? Exchange::kZeroed : Exchange::kLost;
        break;
      }
      a = f;
      // An answer to an earlier frame (e.g. the firmware's answer to a silence): not this one's.
      const std::int32_t behind = static_cast<std::int32_t>(s.seq - f.seq);
      if (behind > 0) {
        ++counters_[pil::kErrSeq];
        continue;
      }
      if (behind < 0) {
        ++counters_[pil::kErrSeq];
        err = "actuator frame " + std::to_string(f.seq) + " answered sensor frame " + std::to_string(s.seq);
        x = Exchange::kZeroed;
      } else if (!codes_in_range(f)) {
        ++code_range_errors_;
        err =
            "actuator frame " + std::to_string(f.seq) + " has a DAC code outside +-" + std::to_string(osc::kDacMaxCode);
        x = Exchange::kZeroed;
      } else {
        x = Exchange::kApplied;
      }
      break;
    }
  }
  // A traced session: the tick's frames end with its trace frame (after its answer and state frames).
  if (traced_ && x != Exchange::kLost) {
    for (;;) {
      FirmwareFrame f;
      const double left = left_s();
      std::string why;
      const Rx r = receive_frame(f, std::max(left, 0.0), why);
      if (r == Rx::kCorrupt) continue;  // counted; the trace may still come
      if (r != Rx::kFrame) {
        err = "no trace frame for sensor frame " + std::to_string(s.seq) + ": " + why;
        x = Exchange::kLost;
        break;
      }
      if (f.type == pil::kActuatorFrame) {  // a stray answer (counted, not applied)
        ++counters_[pil::kErrSeq];
        continue;
      }
      keep(f);
      if (f.type == pil::kTraceFrame && f.trace.seq == s.seq) break;
    }
  }
  if (x != Exchange::kApplied)
    for (std::int32_t& c : a.codes) c = 0;
  return x;
}

std::string PilClient::exit_description() {
  for (int i = 0; i < 100 && !reaped_; ++i) {
    if (waitpid(pid_, &wait_status_, WNOHANG) == pid_)
      reaped_ = true;
    else
      usleep(10000);
  }
  if (!reaped_) return "exited; still running after 1 s";
  if (WIFSIGNALED(wait_status_)) return "killed by signal " + std::to_string(WTERMSIG(wait_status_));
  const int code = WEXITSTATUS(wait_status_);
  // The firmware's own exits (boards/common/cortex_m/startup.cpp); QEMU ends with 0 on the reset
  // that -no-reboot turns into an exit (e.g. the watchdog's).
  const char* what = code == 91   ? ": hard fault"
                     : code == 90 ? ": unexpected interrupt"
                     : code == 0  ? ": a normal end, or a reset under -no-reboot"
                                  : "";
  return "exited, status " + std::to_string(code) + what;
}

bool PilClient::freeze_peer(double seconds, std::string& err) {
  if (!running()) return err = "no peer to freeze", false;
  if (kill(pid_, SIGSTOP) != 0) return err = std::string("SIGSTOP: ") + std::strerror(errno), false;
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  if (kill(pid_, SIGCONT) != 0) return err = std::string("SIGCONT: ") + std::strerror(errno), false;
  return true;
}

int PilClient::stop() {
  if (pid_ <= 0) return -1;
  if (to_child_ >= 0) close(to_child_);
  to_child_ = -1;
  if (reaped_) {
    pid_ = -1;
    reaped_ = false;
    close(from_child_);
    from_child_ = -1;
    return WIFEXITED(wait_status_) ? WEXITSTATUS(wait_status_) : -1;
  }
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
