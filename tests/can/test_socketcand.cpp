// The socketcand server of the host HAL (hal/host: socketcand_proto,
// SocketcandCan, CanTransport): the protocol's text against socketcand's
// documentation and python-can's client (the strings it sends and parses),
// and the server over real TCP sockets on the loopback interface with a
// minimal client written here (the python-can client itself is
// tests/can/test_socketcand.py).
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <chrono>
#include <cstring>
#include <fstream>
#include <netinet/in.h>
#include <poll.h>
#include <string>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>

#include "can_test_frame.hpp"
#include "hal_host/can_transport.hpp"
#include "hal_host/socketcand.hpp"
#include "hal_host/socketcand_proto.hpp"

namespace {

using hal_host::SocketcandCan;
namespace sc = hal_host::socketcand;

bool SameFrame(const mc_hal_can_frame_t& a, const mc_hal_can_frame_t& b) {
  return a.id == b.id && a.flags == b.flags && a.len == b.len &&
         ((a.flags & MC_HAL_CAN_FLAG_RTR) || std::memcmp(a.data, b.data, a.len) == 0);
}

// ----------------------------------------------------------------- text
TEST(SocketcandProto, ParsesWhatPythonCanSends) {
  sc::Command c;
  std::string why;
  // python-can 4.x: f"< send {id:03X} {len:X} " + " ".join(f"{x:x}") + " >"
  ASSERT_TRUE(sc::parse_command(" send 021 8 1 f1 0 ff a b c d ", &c, &why)) << why;
  EXPECT_EQ(sc::Verb::kSend, c.verb);
  EXPECT_TRUE(SameFrame(Fr(0x21, {0x01, 0xF1, 0, 0xFF, 0x0A, 0x0B, 0x0C, 0x0D}), c.frame));
  ASSERT_TRUE(sc::parse_command(" send 1AAAAAAA 2 1 F1 ", &c, &why)) << why;
  EXPECT_TRUE(SameFrame(Fr(0x1AAAAAAA, {0x01, 0xF1}, MC_HAL_CAN_FLAG_EXT), c.frame));
  ASSERT_TRUE(sc::parse_command(" send 123 0 ", &c, &why)) << why;
  EXPECT_TRUE(SameFrame(Fr(0x123, {}), c.frame));
  ASSERT_TRUE(sc::parse_command(" sendrtr 7FF 4 ", &c, &why)) << why;
  EXPECT_EQ(MC_HAL_CAN_FLAG_RTR, c.frame.flags);
  EXPECT_EQ(4u, c.frame.len);
  ASSERT_TRUE(sc::parse_command(" open can0 ", &c, &why));
  EXPECT_EQ(sc::Verb::kOpen, c.verb);
  EXPECT_EQ("can0", c.bus);
  ASSERT_TRUE(sc::parse_command(" rawmode ", &c, &why));
  EXPECT_EQ(sc::Verb::kRawMode, c.verb);
  ASSERT_TRUE(sc::parse_command("bcmmode", &c, &why));
  EXPECT_EQ(sc::Verb::kBcmMode, c.verb);
  ASSERT_TRUE(sc::parse_command(" echo ", &c, &why));
  EXPECT_EQ(sc::Verb::kEcho, c.verb);
}

TEST(SocketcandProto, RefusesMalformedCommandsWithAReason) {
  const char* const bad[][2] = {
      {" send 800 0 ", "identifier '800'"},  // beyond 11 bits
      {" send 20000000 0 ", "identifier"},   // beyond 29 bits
      {" send 1234 0 ", "identifier"},       // 4 digits: neither form
      {" send 12G 0 ", "identifier"},        // not hex
      {" send 123 9 1 2 3 4 5 6 7 8 9 ", "length '9'"},
      {" send 123 2 1 ", "length 2 but 1 data bytes"},
      {" send 123 1 1 2 ", "length 1 but 2 data bytes"},
      {" send 123 1 123 ", "data byte '123'"},
      {" send 123 ", "expected send ID LEN"},
      {" sendrtr 123 ", "expected sendrtr ID DLC"},
      {" open ", "expected open BUS"},
      {" open a_bus_name_too_long_x ", "expected open BUS"},
      {" rawmode now ", "takes no arguments"},
      {" fdsend 123 0 1 00 ", "not supported by this server: fdsend"},
      {" add 1 0 123 8 11 22 33 44 55 66 77 88 ", "not supported by this server: add"},
      {" frame 123 1.0 00 ", "unknown command"},
      {"   ", "empty command"},
  };
  for (const auto& b : bad) {
    sc::Command c;
    std::string why;
    EXPECT_FALSE(sc::parse_command(b[0], &c, &why)) << b[0];
    EXPECT_NE(std::string::npos, why.find(b[1])) << b[0] << " -> " << why;
  }
}

TEST(SocketcandProto, SplitterFindsCommandsAcrossReadsAndResynchronises) {
  sc::CommandSplitter s;
  std::string t;
  s.feed("< open ca", 9);
  EXPECT_EQ(sc::CommandSplitter::Event::kNone, s.next(&t)) << "incomplete: wait";
  s.feed("n0 >\r\n< rawmode >< echo >", 25);
  ASSERT_EQ(sc::CommandSplitter::Event::kCommand, s.next(&t));
  EXPECT_EQ(" open can0 ", t);
  ASSERT_EQ(sc::CommandSplitter::Event::kCommand, s.next(&t));
  EXPECT_EQ(" rawmode ", t);
  ASSERT_EQ(sc::CommandSplitter::Event::kCommand, s.next(&t));
  EXPECT_EQ(" echo ", t);
  EXPECT_EQ(sc::CommandSplitter::Event::kNone, s.next(&t));
  // garbage before a command: one error, then the command
  s.feed("hello< echo >", 13);
  ASSERT_EQ(sc::CommandSplitter::Event::kError, s.next(&t));
  EXPECT_EQ("bytes outside a command", t);
  ASSERT_EQ(sc::CommandSplitter::Event::kCommand, s.next(&t));
  // a command cut by the next '<'
  s.feed("< send 123 < echo >", 19);
  ASSERT_EQ(sc::CommandSplitter::Event::kError, s.next(&t));
  EXPECT_EQ("command not closed before the next one", t);
  ASSERT_EQ(sc::CommandSplitter::Event::kCommand, s.next(&t));
  EXPECT_EQ(" echo ", t);
  // a control byte inside
  s.feed("< ec\x01ho >", 9);
  ASSERT_EQ(sc::CommandSplitter::Event::kError, s.next(&t));
  EXPECT_NE(std::string::npos, t.find("not printable"));
  // over-long: refused once, the rest up to its '>' dropped, then in step again
  const std::string longcmd = "< " + std::string(300, 'x');
  s.feed(longcmd.data(), longcmd.size());
  ASSERT_EQ(sc::CommandSplitter::Event::kError, s.next(&t));
  EXPECT_EQ("command longer than 256 bytes", t);
  EXPECT_EQ(0u, s.buffered()) << "the buffer stays bounded";
  s.feed(std::string(1000, 'y').data(), 1000);
  EXPECT_EQ(sc::CommandSplitter::Event::kNone, s.next(&t));
  EXPECT_EQ(0u, s.buffered());
  s.feed("yy >< echo >", 12);
  ASSERT_EQ(sc::CommandSplitter::Event::kCommand, s.next(&t));
  EXPECT_EQ(" echo ", t);
}

TEST(SocketcandProto, FramesAreWrittenAsSocketcandAndPythonCanReadThem) {
  // socketcand's raw mode: "< frame %03X %ld.%06ld " then "%02X" per byte, " >"
  EXPECT_EQ("< frame 021 1.250000 0A00FF >", sc::format_frame(1.25, Fr(0x21, {0x0A, 0, 0xFF})));
  EXPECT_EQ("< frame 12345678 0.000001  >",
            sc::format_frame(1e-6, Fr(0x12345678, {}, MC_HAL_CAN_FLAG_EXT)));
  mc_hal_can_frame_t r = Fr(0x7FF, {});
  r.flags = MC_HAL_CAN_FLAG_RTR;
  r.len = 4;
  EXPECT_EQ("< rtr 7FF 2.000000 4 >", sc::format_frame(2.0, r));
  // the microsecond as the candump log rounds it (hal_host::candump_format)
  EXPECT_EQ("< frame 021 12.345679 01 >", sc::format_frame(12.3456789, Fr(0x21, {1})));
  EXPECT_EQ("< send 021 3 a 0 ff >", sc::format_send(Fr(0x21, {0x0A, 0, 0xFF})));
  EXPECT_EQ("< error bad ?x? >", sc::format_error("bad <x>"));
}

// --------------------------------------------------------------- server
// A blocking TCP client with a receive timeout.
class Client {
 public:
  explicit Client(uint16_t port, int rcvbuf = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (rcvbuf > 0) (void)setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    struct sockaddr_in a {};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ok_ = ::connect(fd_, reinterpret_cast<struct sockaddr*>(&a), sizeof a) == 0;
  }
  ~Client() { Close(); }
  void Close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  bool ok() const { return ok_; }
  int fd() const { return fd_; }
  void Send(const std::string& s) {
    ASSERT_EQ(static_cast<ssize_t>(s.size()), ::send(fd_, s.data(), s.size(), MSG_NOSIGNAL));
  }
  // What has arrived within wait_s while the server is served meanwhile.
  std::string Read(SocketcandCan& srv, double wait_s = 0.2, bool peek = false) {
    std::string got;
    const auto t_end = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
    while (std::chrono::steady_clock::now() < t_end) {
      srv.service();
      char b[4096];
      const ssize_t n = ::recv(fd_, b, sizeof b, MSG_DONTWAIT | (peek ? MSG_PEEK : 0));
      if (n > 0) {
        if (peek) return std::string(b, static_cast<size_t>(n));
        got.append(b, static_cast<size_t>(n));
      } else if (n == 0) {
        got += "<EOF>";
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return got;
  }
  // Exactly n bytes (blocking).
  std::string Take(size_t n) {
    std::string got(n, '\0');
    size_t have = 0;
    while (have < n) {
      const ssize_t k = ::recv(fd_, &got[have], n - have, 0);
      if (k <= 0) break;
      have += static_cast<size_t>(k);
    }
    return got.substr(0, have);
  }
  // Handshake as python-can does it.
  void Raw(SocketcandCan& srv) {
    ASSERT_EQ("< hi >", Read(srv, 0.1));
    Send("< open can0 >");
    ASSERT_EQ("< ok >", Read(srv, 0.1));
    Send("< rawmode >");
    ASSERT_EQ("< ok >", Read(srv, 0.1));
  }

 private:
  int fd_ = -1;
  bool ok_ = false;
};

struct Server : ::testing::Test {
  double t_s = 0.5;
  SocketcandCan srv{"127.0.0.1", 0, "can0", [this]() { return t_s; }, []() { return 42u; }};
};

TEST_F(Server, ServesSeveralClientsFramesBothWays) {
  ASSERT_NE(0, srv.port()) << "port 0: the kernel chose one";
  Client a(srv.port()), b(srv.port());
  ASSERT_TRUE(a.ok() && b.ok());
  a.Raw(srv);
  b.Raw(srv);
  EXPECT_EQ(2u, srv.raw_clients());
  // the drive's frame to both
  const mc_hal_can_frame_t hb = Fr(0x21, {1, 2, 3, 4, 5, 6, 7, 8});
  ASSERT_EQ(0, mc_hal_can_send(srv.hal(), &hb));
  EXPECT_EQ("< frame 021 0.500000 0102030405060708 >", a.Read(srv, 0.1));
  EXPECT_EQ("< frame 021 0.500000 0102030405060708 >", b.Read(srv, 0.1));
  // a client's frame to the drive and to the other client, not back to it
  a.Send("< send 037 1 5 >");
  t_s = 0.75;
  mc_hal_can_frame_t got{};
  EXPECT_EQ("< frame 037 0.750000 05 >", b.Read(srv, 0.1));
  ASSERT_EQ(0, mc_hal_can_receive(srv.hal(), &got));
  EXPECT_TRUE(SameFrame(Fr(0x37, {5}), got));
  EXPECT_EQ(42u, got.timestamp_ticks) << "stamped with the board's ticks";
  EXPECT_EQ(-EAGAIN, mc_hal_can_receive(srv.hal(), &got));
  EXPECT_EQ("", a.Read(srv, 0.05)) << "not echoed to its sender";
  a.Send("< echo >");
  EXPECT_EQ("< echo >", a.Read(srv, 0.1));
  // bcmmode: no more frames to that client
  b.Send("< bcmmode >");
  EXPECT_EQ("< ok >", b.Read(srv, 0.1));
  ASSERT_EQ(0, mc_hal_can_send(srv.hal(), &hb));
  EXPECT_EQ("", b.Read(srv, 0.05));
  EXPECT_EQ(2u, srv.stats().tx_frames);
  EXPECT_EQ(1u, srv.stats().rx_frames);
}

TEST_F(Server, MalformedInputIsRefusedAndChangesNothing) {
  Client a(srv.port());
  a.Raw(srv);
  a.Send("< send 800 1 00 >< send 021 2 1 >garbage< frobnicate >");
  const std::string r = a.Read(srv, 0.1);
  EXPECT_EQ(
      "< error identifier '800': 1 to 3 hex digits up to 7FF, or 8 up to 1FFFFFFF >"
      "< error send: length 2 but 1 data bytes >< error bytes outside a command >"
      "< error unknown command >",
      r);
  mc_hal_can_frame_t got{};
  EXPECT_EQ(-EAGAIN, mc_hal_can_receive(srv.hal(), &got)) << "nothing reached the drive";
  EXPECT_EQ(4u, srv.stats().commands_refused);
  // still connected and in raw mode
  const mc_hal_can_frame_t f = Fr(0x21, {9});
  ASSERT_EQ(0, mc_hal_can_send(srv.hal(), &f));
  EXPECT_EQ("< frame 021 0.500000 09 >", a.Read(srv, 0.1));
  // a command before the bus is open; then another bus: refused and closed
  Client b(srv.port());
  EXPECT_EQ("< hi >", b.Read(srv, 0.1));
  b.Send("< send 021 0 >");
  EXPECT_EQ("< error open the bus first: open can0 >", b.Read(srv, 0.1));
  b.Send("< open can1 >");
  EXPECT_EQ("< error could not open bus ><EOF>", b.Read(srv, 0.3));
  EXPECT_EQ(-EAGAIN, mc_hal_can_receive(srv.hal(), &got));
}

TEST_F(Server, HoldsFramesUntilTheClientReadTheRawModeReply) {
  // python-can's client compares the whole of one recv() with "< ok >"
  Client a(srv.port());
  EXPECT_EQ("< hi >", a.Read(srv, 0.1));
  a.Send("< open can0 >");
  EXPECT_EQ("< ok >", a.Read(srv, 0.1));
  a.Send("< rawmode >");
  // the reply arrives and is not read; the drive goes on sending
  for (int i = 0; i < 5; ++i) {
    srv.service();
    const mc_hal_can_frame_t f = Fr(0x21, {static_cast<uint8_t>(i)});
    ASSERT_EQ(0, mc_hal_can_send(srv.hal(), &f));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  // longer than the fallback hold (kRawHoldFallbackS) that serves where the
  // kernel cannot say whether the client read (sock_diag)
  EXPECT_EQ("< ok >", a.Read(srv, 1.5 * SocketcandCan::kRawHoldFallbackS, true))
      << "only the reply is in the socket (peek)";
  EXPECT_EQ(0u, srv.raw_clients()) << "held";
  EXPECT_EQ("< ok >", a.Take(6));
  // once read, the held frames follow, none lost
  const std::string rest = a.Read(srv, 0.2);
  EXPECT_EQ(
      "< frame 021 0.500000 00 >< frame 021 0.500000 01 >< frame 021 0.500000 02 >"
      "< frame 021 0.500000 03 >< frame 021 0.500000 04 >",
      rest);
  EXPECT_EQ(1u, srv.raw_clients());
  EXPECT_EQ(1u, srv.stats().raw_holds_seen_read) << "released because the client read";
}

TEST_F(Server, ClientsComeAndGoAndTheRunEndsWithEverythingSent) {
  {
    Client a(srv.port());
    a.Raw(srv);
    a.Send("< send 037 1 ");  // half a command, then gone
  }
  for (int i = 0; i < 20; ++i) srv.service();
  EXPECT_EQ(0u, srv.clients());
  mc_hal_can_frame_t got{};
  EXPECT_EQ(-EAGAIN, mc_hal_can_receive(srv.hal(), &got));
  Client b(srv.port());
  b.Raw(srv);
  EXPECT_EQ(1u, srv.stats().clients_max) << "the first was gone";
  for (int i = 0; i < 2000; ++i) {
    const mc_hal_can_frame_t f = Fr(0x21, {static_cast<uint8_t>(i)});
    ASSERT_EQ(0, mc_hal_can_send(srv.hal(), &f));
  }
  EXPECT_TRUE(srv.finish(5.0));
  std::string all = b.Read(srv, 0.3);
  size_t n = 0;
  for (size_t p = all.find("< frame"); p != std::string::npos; p = all.find("< frame", p + 1)) ++n;
  EXPECT_EQ(2000u, n) << "every frame queued before the end arrives";
  EXPECT_EQ("<EOF>", all.substr(all.size() - 5));
  EXPECT_EQ(0u, srv.stats().unflushed_clients);
  Client c(srv.port());
  EXPECT_FALSE(c.ok()) << "no longer listening";
}

TEST(SocketcandServer, BoundsWhatItQueuesForAClientThatDoesNotRead) {
  // a 4 KiB queue per client (the default is kMaxClientQueueBytes)
  SocketcandCan srv(
      "127.0.0.1", 0, "can0", []() { return 1.0; }, nullptr, 4096);
  // small receive buffers: TCP's own buffers fill sooner
  Client slow(srv.port(), 4096), talker(srv.port(), 4096);
  slow.Raw(srv);
  // the kernel's buffers take the first megabytes: send until the server
  // has to drop frames for this client
  const mc_hal_can_frame_t f = Fr(0x21, {1, 2, 3, 4, 5, 6, 7, 8});
  for (int i = 0; i < 1000000 && srv.stats().tx_client_drops == 0; ++i) {
    ASSERT_EQ(0, mc_hal_can_send(srv.hal(), &f));
  }
  EXPECT_GT(srv.stats().tx_client_drops, 0u) << "dropped for it and counted";
  EXPECT_EQ(1u, srv.raw_clients()) << "a slow reader stays connected";
  // one that sends commands and never reads their replies is disconnected
  EXPECT_EQ("< hi >", talker.Read(srv, 0.1));
  std::string echoes;
  for (int i = 0; i < 4000; ++i) echoes += "< echo >";
  bool gone = false;
  for (int round = 0; round < 5000 && !gone; ++round) {
    (void)::send(talker.fd(), echoes.data(), echoes.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    srv.service();
    gone = srv.clients() == 1;
  }
  EXPECT_TRUE(gone) << "the talker was disconnected";
  EXPECT_EQ(1u, srv.raw_clients());
}

TEST(SocketcandServer, RefusesAnAddressItCannotUse) {
  auto mk = [](const char* host, uint16_t port) {
    return SocketcandCan(host, port, "can0", []() { return 0.0; });
  };
  EXPECT_THROW(mk("no.such.host", 0), std::runtime_error);
  SocketcandCan a("localhost", 0, "can0", []() { return 0.0; });
  try {
    mk("127.0.0.1", a.port());
    FAIL() << "the port is taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string::npos, std::string(e.what()).find("Address already in use")) << e.what();
  }
}

// ----------------------------------------------------------- transport
TEST(CanTransport, ParsesTheSocketcandInterface) {
  std::string host, why;
  uint16_t port = 1;
  EXPECT_TRUE(
      hal_host::parse_socketcand_interface("socketcand:127.0.0.1:29536", &host, &port, &why));
  EXPECT_EQ("127.0.0.1", host);
  EXPECT_EQ(29536, port);
  EXPECT_FALSE(hal_host::parse_socketcand_interface("vcan0", &host, &port, &why));
  EXPECT_TRUE(why.empty()) << "not socketcand at all";
  for (const char* bad :
       {"socketcand:", "socketcand:127.0.0.1", "socketcand::1", "socketcand:127.0.0.1:65536",
        "socketcand:127.0.0.1:-1", "socketcand:127.0.0.1:12x"}) {
    EXPECT_FALSE(hal_host::parse_socketcand_interface(bad, &host, &port, &why)) << bad;
    EXPECT_NE(std::string::npos, why.find("socketcand:HOST:PORT")) << bad;
  }
}

TEST(CanTransport, ReplaysTheCommandScriptOnALiveTransport) {
  const std::string script = ::testing::TempDir() + "/mc_sc_script.log";
  {
    std::ofstream f(script);
    f << "(0.100000) can0 031#01\n(0.200000) can0 030#01\n";
  }
  double t = 0.0;
  hal_host::CanTransportConfig c;
  c.interface = "socketcand:127.0.0.1:0";
  c.script_path = script;
  c.now_s = [&t]() { return t; };
  hal_host::CanTransport tr(c);
  Client a(tr.socketcand()->port());
  a.Raw(*tr.socketcand());
  mc_hal_can_frame_t got{};
  EXPECT_EQ(-EAGAIN, mc_hal_can_receive(tr.hal(), &got));
  t = 0.15;
  ASSERT_EQ(0, mc_hal_can_receive(tr.hal(), &got));
  EXPECT_TRUE(SameFrame(Fr(0x31, {1}), got));
  a.Send("< send 037 1 1 >");
  (void)a.Read(*tr.socketcand(), 0.05);
  t = 0.25;
  ASSERT_EQ(0, mc_hal_can_receive(tr.hal(), &got));
  EXPECT_TRUE(SameFrame(Fr(0x30, {1}), got)) << "the script's frame first";
  ASSERT_EQ(0, mc_hal_can_receive(tr.hal(), &got));
  EXPECT_TRUE(SameFrame(Fr(0x37, {1}), got)) << "then the bus";
  std::map<std::string, double> num;
  std::map<std::string, std::string> txt;
  EXPECT_TRUE(tr.finish());
  tr.report(&num, &txt);
  EXPECT_EQ(2.0, num["can_script_frames"]);
  EXPECT_EQ(1.0, num["socketcand_rx_frames"]);
  EXPECT_EQ("socketcand:127.0.0.1:" + std::to_string(tr.socketcand()->port()),
            txt["can_interface"]);
  c.interface = "socketcand:127.0.0.1";
  EXPECT_THROW(hal_host::CanTransport bad(c), std::runtime_error);
}

}  // namespace
