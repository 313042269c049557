// Writing a host tool's output file by what is at its path, so that nothing there is lost or turned
// into something it was not:
//   "-"                         standard output;
//   a regular file, a new path  a temporary file beside it, renamed over it when complete: a reader
//                               sees the old file or the new one whole, and a failed write (a full
//                               disk) leaves the old one as it was; a replaced file keeps its mode;
//   a symbolic link             written through to its target, as above (the link stays a link);
//   a device, a FIFO, a socket  written in place (opened for writing; /dev/stdout, a named pipe);
//   a directory                 an error.
// Every failed write, flush or close is an error naming the path and the system's reason.
#pragma once

#include <string>

namespace sim {

/// Before a long run: whether `path` can take an output (its directory is writable, a device or FIFO
/// is writable); creates nothing that stays and never opens a FIFO (that would block).
bool check_output(const std::string& path, std::string& err);

/// Writes `text` to `path` as above.
bool write_output(const std::string& path, const std::string& text, std::string& err);

/// Writes all of `text` to an open descriptor; false with `err` ("cannot write NAME: reason").
bool write_all(int fd, const std::string& text, const std::string& name, std::string& err);

/// Whether `path` is this process's standard output ("-", or the file or pipe that fd 1 is).
bool is_stdout(const std::string& path);

}  // namespace sim
