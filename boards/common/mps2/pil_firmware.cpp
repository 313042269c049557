// The processor-in-the-loop firmware for the MPS2 boards, in the board's scalar (board::Scalar: float
// on the AN386's Cortex-M4F, Q12.19 fixed point on the AN385's Cortex-M3): a link (osc/link/frames.hpp)
// carries the frames to the simulated PUMA 560 in host_sim. The control interrupt (TIMER0's vector)
// runs the control task; here it is pended whenever a frame ends (valid or not), so the host's plant
// sets the sample clock (lockstep) and the run is deterministic under -icount. Every link error is
// answered at once with zero codes (osc/link/node.hpp). The link watchdog answers a missing or short
// frame the same way after params::kLinkTimeout of virtual time: in lockstep the host paces the
// ticks, so the node's tick-based silence rule (params::kLinkSilenceTicks) has no ticks to count.
//
// Two transports for the same bytes, chosen at start from the command line QEMU passes over
// semihosting (-semihosting-config ...,arg=link=semihosting):
//   UART0 (the default): the board's serial port, a byte at a time through QEMU's CMSDK UART model,
//     as on a board. The main loop sleeps (WFI) until a byte comes or the wake-up timer ticks, and
//     checks the link timeout.
//   "link=semihosting": whole reads and writes of the semihosting console (":tt", QEMU's own
//     stdin and stdout), for speed: QEMU's UART model costs a host system call or two per byte, this
//     one a call per read or write (docs/benchmarks.md, "QEMU"). The main loop blocks in the read,
//     and so does virtual time (the core executes nothing and is not idle): nothing can time out
//     while the host computes, so this transport has no link timeout. A frame that never completes
//     leaves the firmware waiting; the host's own timeout reports it. The link's timeouts are tested
//     over the UART.
// The node, the frames, the ticks and what they compute are the same on both: the same run gives
// the same torques, bit for bit (tests/host_sim/test_pil.cpp, PilQemu).
//
// The parameter store: with "params=PATH" on the semihosting command line (osc_sim --qemu --param-file) a host file
// through semihosting stands for the board's flash (semihost_flash.hpp, the virtual board's image format), its
// newest record applied before the link starts, as a board's boot applies it; without, the command port's RAM.
//
// The command protocol (docs/protocol.md): a command or a setpoint frame is no tick (on_byte returns
// false); the node prepares it here in the main loop (a move's plan and path check, up to about half
// a million instructions on the M3), never in the control interrupt, whose tick only writes the
// answer, state and trace frames after its actuator frame. In lockstep nothing else runs meanwhile:
// the host waits for the tick's frames before it sends the next.
//
// The CMSDK watchdog (board.hpp) starts with the link (the first received byte). Its PIL policy
// (docs/firmware.md, "Watchdog"): it is fed at the end of every healthy tick, and by the main loop
// while it waits for the host's next frame, once per control period, provided every tick it pended
// has run. The host sets the pace and may take far longer than the 8 ms to the reset between two
// frames (virtual time advances while the main loop waits), so ticks alone cannot feed it here. A
// hung or disabled control interrupt or a hung main loop lets it expire; a latched fault does not:
// the link keeps answering every frame with zero torque and the latched bits, which the host needs.
// While the main loop waits for the next byte with every pended tick done, the watchdog is
// paused, and restarted from a full count after the wait: under -icount (sleep=on) virtual time
// follows wall-clock time while the core sleeps, including any time QEMU itself is descheduled, in
// one jump. (Stopping it was not enough: QEMU 7.2's model counts on and latches its reset when two
// expiries fit in one such jump, and a loaded machine reset the firmware that way; the pause sets
// the longest count: cmsdk::Watchdog::pause. Test: Link.SlowHostOrDescheduledEmulator...)
// Feeding never changes what a tick computes, so the lockstep run stays deterministic.
#include <cstdint>

#include "board.hpp"
#include "osc/control/params.hpp"
#include "osc/link/identify_port.hpp"
#include "osc/link/node.hpp"
#include "osc/robot.hpp"
#include "param_store.hpp"
#include "semihost_flash.hpp"

namespace {

enum class Transport : std::uint8_t { kUart, kSemihosting };
Transport g_transport = Transport::kUart;
int g_console_in = -1, g_console_out = -1;  // semihosting handles (kSemihosting)

bool g_link_up = false;  // the first byte came: the CMSDK watchdog runs

struct Mps2Board {
  static void link_write(const std::uint8_t* p, int n) {
    if (g_transport == Transport::kSemihosting)
      board::semihost::write(g_console_out, p, n);
    else
      board::uart_write(p, n);
  }
  static std::uint32_t cycles() { return board::cycles(); }
  static std::uint32_t stack_used() { return board::stack_used_sweep(); }  // every tick: a bounded sweep
  static void burn(std::uint32_t ns) { board::busy_wait(ns); }
  static void fault_output(bool active) { board::fault_output(active); }
  /// Long work of the main loop's (PilNode::computing, follow_identify): every pended tick has run and in lockstep
  /// none is due until the main loop pends it, so the watchdog pauses as while the main loop waits for the host, and
  /// restarts from a full count after it. A hung tick still lets it expire: the work it pre-empts never ends.
  static void computing(bool begin) {
    if (!g_link_up) return;
    if (begin)
      board::watchdog_pause();
    else
      board::watchdog_start();
  }
};
static_assert(osc::PilBoard<Mps2Board>);
static_assert(hal::ControlHal<osc::PilNode<board::Scalar, Mps2Board>>);
static_assert(hal::CurrentHal<osc::PilNode<board::Scalar, Mps2Board>>, "the host's amplifiers over the link");

osc::PilNode<board::Scalar, Mps2Board> g_node;  // a few kB: static, never on the stack

/// Overrun budget: one control period in virtual ns (= instructions under -icount shift=0).
constexpr std::uint32_t kPeriodNs = 1000000000u / board::kControlHz;
constexpr std::uint32_t kLinkTimeoutNs = static_cast<std::uint32_t>(osc::params::kLinkTimeout * 1e9);

// Ticks pended by the main loop and ticks run by the control interrupt: equal when none is stuck.
volatile std::uint32_t g_ticks_pended = 0, g_ticks_run = 0;

void pend_tick() {
  g_ticks_pended = g_ticks_pended + 1;
  board::control_irq_pend();  // the tick runs now
}

// The board's own estimate of an identify run (osc/link/identify_port.hpp): after every tick the main loop takes the
// run's newest sample into the estimate's sums, and when the run's motion ends it solves the estimate and writes the
// identify frame after that tick's frames. The sums and the solve are doubles (soft-float on both cores): about
// 20 kB, static.
osc::IdentifyPort<board::Scalar> g_identify;
std::uint32_t g_ticks_followed = 0;

/// The identify run followed after the ticks run since the last call (in lockstep one: the main loop pends each).
void follow_identify() {
  if (g_ticks_run == g_ticks_followed) return;
  g_ticks_followed = g_ticks_run;
  // The estimate's solve at the run's end: tens of millions of instructions (soft-float doubles), as long work. Only
  // while a run is followed: otherwise the call is a check of the tick's report.
  const bool following = g_identify.active();
  if (following) Mps2Board::computing(true);
  g_identify.after_tick(g_node.task, Mps2Board::link_write);
  if (following) Mps2Board::computing(false);
}

/// The semihosting command line (QEMU: -semihosting-config arg=..., its words joined by spaces).
struct CommandLine {
  char text[256];
  int n = 0;
  CommandLine() { n = board::semihost::command_line(text, sizeof text); }
  /// The word starting with `prefix` (length k): the index of what follows the prefix, or -1.
  int word(const char* prefix, int k) const {
    for (int i = 0; i + k <= n; ++i) {
      if (i > 0 && text[i - 1] != ' ') continue;
      int j = 0;
      while (j < k && text[i + j] == prefix[j]) ++j;
      if (j == k) return i + k;
    }
    return -1;
  }
  /// Whether `w` (length k) is a whole word of the line.
  bool has(const char* w, int k) const {
    const int at = word(w, k);
    return at >= 0 && (at == n || text[at] == ' ');
  }
};

/// "link=semihosting" is a word of the command line.
bool semihosting_link_requested(const CommandLine& line) {
  constexpr char kWord[] = "link=semihosting";
  return line.has(kWord, sizeof kWord - 1);
}

// The parameter store in a host file when the command line has "params=PATH" (osc_sim --qemu --param-file: a power
// cycle of the image), else in the command port's RAM (lost when QEMU ends). semihost_flash.hpp says why a file.
board::SemihostFlash<persist::kImageSectorWords> g_flash;
persist::NoWatchdog g_no_watchdog;  // a save is a few semihosting calls: no stall for the watchdog to outlast
persist::FlashParamStore<board::SemihostFlash<persist::kImageSectorWords>, persist::NoWatchdog> g_params{g_flash,
                                                                                                         g_no_watchdog};

/// With "params=PATH": the store on that file, its newest record applied to the task as a board's boot applies it
/// (a record the task refuses, or none: the defaults). Before the link starts; the node applies it again when the
/// host's first frame starts the task disabled (PilNode::configure).
void open_param_store(const CommandLine& line) {
  constexpr char kWord[] = "params=";
  const int at = line.word(kWord, sizeof kWord - 1);
  if (at < 0) return;
  char path[sizeof line.text];
  std::uint32_t k = 0;
  for (int i = at; i < line.n && line.text[i] != ' '; ++i) path[k++] = line.text[i];
  path[k] = 0;
  if (k == 0 || !g_flash.open(path, k)) return;
  g_node.port.set_param_storage(g_params.storage());
  g_node.port.apply_stored(g_node.task);  // and again when the host's first frame re-initialises the task (node.hpp)
}

/// The received bytes of the semihosting transport: one read's worth at a time.
struct ConsoleRx {
  std::uint8_t buf[64];
  int len = 0, pos = 0;
  bool ready() const { return pos < len; }
  std::uint8_t read() { return buf[pos++]; }
  /// Blocks until the host writes. At the end of the input the host has gone: the run ends.
  void wait() {
    const int left = board::semihost::read(g_console_in, buf, static_cast<int>(sizeof buf));
    len = static_cast<int>(sizeof buf) - left;
    pos = 0;
    if (len <= 0) board::semihost::exit(0);
  }
};
ConsoleRx g_console_rx;

bool rx_ready() { return g_transport == Transport::kSemihosting ? g_console_rx.ready() : board::uart_rx_ready(); }
std::uint8_t rx_read() { return g_transport == Transport::kSemihosting ? g_console_rx.read() : board::uart_read(); }
/// Waits for the next byte: the UART sleeps until a byte or an interrupt; the console blocks until
/// bytes come.
void rx_wait() {
  if (g_transport == Transport::kSemihosting)
    g_console_rx.wait();
  else
    board::sleep_until_rx_or_irq();
}

}  // namespace

extern "C" void TIMER0_Handler() {
  board::control_timer_ack();
  g_node.tick();
  g_ticks_run = g_ticks_run + 1;
  if (osc::supervisor_healthy(g_node.task.sup)) board::watchdog_feed();
}

// The watchdog's first expiry: fault line active, the cause noted, then the reset (under -no-reboot
// QEMU ends and the host reports the closed link).
extern "C" void NMI_Handler() {
  board::watchdog_expired(g_node.task.sup.latched);
  board::await_reset();
}

// Wake-ups from WFI: a received byte, and the wake-up timer (the main loop's time-based checks).
extern "C" void UART0RX_Handler() { board::uart_rx_irq_ack(); }
extern "C" void TIMER1_Handler() { board::wake_timer_ack(); }

int main() {
  board::cycle_counter_init();
  const CommandLine line;
  if (semihosting_link_requested(line)) {
    g_console_in = board::semihost::open(":tt", 3, 0);
    g_console_out = board::semihost::open(":tt", 3, 4);
    if (g_console_in < 0 || g_console_out < 0) board::semihost::exit(2);
    g_transport = Transport::kSemihosting;
  } else {
    board::uart_init();
  }
  g_node.init(osc::joint_vector<board::Scalar>(osc::robot::kQStart), osc::FrictionMode::kAdaptive, kPeriodNs);
  open_param_store(line);
  board::control_irq_enable();
  if (g_transport == Transport::kUart) {
    board::uart_rx_irq_enable();
    board::wake_timer_start(board::kControlHz);  // nothing can wake a core blocked in a console read
  }
  g_node.hello();  // bytes the host sent before this point may have been dropped
  // The main loop waits (rx_wait) until a byte comes or, on the UART, the wake-up timer ticks (once
  // per control period), and then handles every byte that is there. Under -icount (sleep=on, QEMU's default)
  // virtual time follows the host's wall-clock time while the core sleeps, as it did while it
  // polled; the sleep hands the CPU to QEMU's I/O thread at once, which delivers the next byte (a
  // polling loop keeps it waiting: docs/benchmarks.md). The link watchdog and the CMSDK watchdog
  // are armed by the first byte. Virtual time runs on while the host computes its next frame, so
  // the time between frames follows the host's wall-clock time (the frames carry the longest gap
  // seen).
  std::uint32_t last = board::cycles(), last_feed = last;
  for (;;) {
    follow_identify();
    if (rx_ready()) {
      if (!g_link_up) {
        g_link_up = true;
        board::watchdog_start();
        last_feed = board::cycles();
      }
      g_node.on_byte(rx_read(), pend_tick);
      last = board::cycles();
      continue;
    }
    if (g_link_up) {
      const std::uint32_t now = board::cycles();
      if (now - last > kLinkTimeoutNs) {
        g_node.on_timeout(pend_tick);
        last = board::cycles();
        continue;
      }
      if (now - last_feed >= kPeriodNs && g_ticks_run == g_ticks_pended) {
        board::watchdog_feed();  // waiting for the host, every pended tick done
        last_feed = now;
      }
    }
    // Waiting for the host with every pended tick done, the watchdog pauses during the wait and
    // restarts from a full count after it: virtual time jumps while QEMU itself is descheduled,
    // and such a jump must not read as a hung firmware. A tick still pending keeps it counting.
    const bool pause = g_link_up && g_ticks_run == g_ticks_pended;
    if (pause) board::watchdog_pause();
    rx_wait();
    if (pause) {
      board::watchdog_start();
      last_feed = board::cycles();
    }
  }
}
