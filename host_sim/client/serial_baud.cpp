// A baud rate outside termios's B-constants through Linux's termios2 (BOTHER): kept apart from
// osc_client.cpp because <asm/termbits.h> and <termios.h> declare the same names.
#include <asm/termbits.h>
#include <sys/ioctl.h>

namespace osc::client {

bool set_custom_baud(int fd, int baud) {
  struct termios2 t {};
  if (ioctl(fd, TCGETS2, &t) != 0) return false;
  t.c_cflag &= ~(CBAUD | (CBAUD << IBSHIFT));
  t.c_cflag |= BOTHER | (BOTHER << IBSHIFT);
  t.c_ispeed = static_cast<speed_t>(baud);
  t.c_ospeed = static_cast<speed_t>(baud);
  return ioctl(fd, TCSETS2, &t) == 0;
}

}  // namespace osc::client
