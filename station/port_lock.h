#pragma once
// A serial port held by this process alone (station-internal, used by serial_transport.cc): the
// path must be a character device that is a tty; it is opened, locked with flock (LOCK_EX, never
// waited on) and made exclusive with TIOCEXCL (a second open() of the tty by anyone but root fails
// with EBUSY) for as long as the descriptor stays open. A port in use, by another irdist (flock)
// or by a program that set TIOCEXCL, is refused naming its holder's pid and command where
// /proc/locks tells them.

#include <string>

namespace irdist {

// Opens `path` exclusively; returns the open, locked descriptor (non-blocking, no controlling
// tty, close-on-exec). `origin` names where the port was given, for the fix. Throws LinkError.
int OpenExclusivePort(const std::string& path, const std::string& origin);

// Clears TIOCEXCL (the flag would outlive this process on a tty another process keeps open, as
// the emulators' ptys do) and closes the descriptor, which drops the flock.
void CloseExclusivePort(int fd) noexcept;

// The process holding an flock on `path`'s file, from /proc/locks: "process 1234 (irdist station
// move 10)", or "" when no holder is found.
std::string PortLockHolder(const std::string& path);

}  // namespace irdist
