#pragma once
// Moves the calling process into a network namespace of its own whose only interface is a
// loopback with multicast, so LCM's UDP multicast (udpm) works and no datagram can reach any
// other machine or process. Call before the process starts a thread: a new user namespace
// (needed when not root) requires a single-threaded caller. Root (also inside a chroot, where
// a user namespace is refused) needs only the network namespace.

#include <arpa/inet.h>
#include <fcntl.h>
#include <net/if.h>
#include <net/route.h>
#include <netinet/in.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace fullarm::hil::test {

namespace detail {
inline bool writeFile(const char* path, const std::string& text) {
  const int fd = ::open(path, O_WRONLY);
  if (fd < 0) return false;
  const bool ok = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  ::close(fd);
  return ok;
}
}  // namespace detail

/// Enters the private network once per process; returns "" on success, else what failed.
inline std::string enterPrivateNetwork() {
  static std::string result = [] {
    const uid_t uid = ::geteuid();
    const gid_t gid = ::getegid();
    if (uid == 0) {
      if (::unshare(CLONE_NEWNET) != 0) return std::string("unshare(CLONE_NEWNET): ") + std::strerror(errno);
    } else {
      if (::unshare(CLONE_NEWUSER | CLONE_NEWNET) != 0) {
        return std::string("unshare(CLONE_NEWUSER | CLONE_NEWNET): ") + std::strerror(errno);
      }
      if (!detail::writeFile("/proc/self/setgroups", "deny") ||
          !detail::writeFile("/proc/self/uid_map", "0 " + std::to_string(uid) + " 1") ||
          !detail::writeFile("/proc/self/gid_map", "0 " + std::to_string(gid) + " 1")) {
        return std::string("mapping the user namespace: ") + std::strerror(errno);
      }
    }
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    if (fd < 0) return std::string("socket: ") + std::strerror(errno);
    ifreq ifr{};
    std::strncpy(ifr.ifr_name, "lo", IFNAMSIZ - 1);
    if (::ioctl(fd, SIOCGIFFLAGS, &ifr) != 0) return std::string("SIOCGIFFLAGS lo: ") + std::strerror(errno);
    ifr.ifr_flags = static_cast<short>(ifr.ifr_flags | IFF_UP | IFF_MULTICAST);
    if (::ioctl(fd, SIOCSIFFLAGS, &ifr) != 0) return std::string("SIOCSIFFLAGS lo up multicast: ") + std::strerror(errno);
    // Route 224.0.0.0/4 to the loopback.
    rtentry rt{};
    auto* dst = reinterpret_cast<sockaddr_in*>(&rt.rt_dst);
    dst->sin_family = AF_INET;
    dst->sin_addr.s_addr = htonl(0xE0000000u);
    auto* mask = reinterpret_cast<sockaddr_in*>(&rt.rt_genmask);
    mask->sin_family = AF_INET;
    mask->sin_addr.s_addr = htonl(0xF0000000u);
    rt.rt_flags = RTF_UP;
    char lo[] = "lo";
    rt.rt_dev = lo;
    if (::ioctl(fd, SIOCADDRT, &rt) != 0) return std::string("SIOCADDRT 224.0.0.0/4 dev lo: ") + std::strerror(errno);
    ::close(fd);
    return std::string();
  }();
  return result;
}

}  // namespace fullarm::hil::test
