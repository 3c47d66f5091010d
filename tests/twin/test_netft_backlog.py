"""The twin's Net F/T never sends a backlog: samples more than 10 ms past their time are dropped,
as the device never has them (a backlog sent at the rate kept every later record 0.8 s late on
a loaded host)."""

from __future__ import annotations

import socket
import struct

from ftcomp.twin.netft import NETFT_HTTP_PORT, RDT_PORT, NetFtServer, bind_socket
from standins.launch import loopback_address

RECORD = struct.Struct(">III6i")


def test_a_sender_held_back_sends_the_newest_samples_not_the_backlog() -> None:
    host = loopback_address("twin_netft_backlog")
    server = NetFtServer(
        bind_socket(host, RDT_PORT, socket.SOCK_DGRAM),
        bind_socket(host, NETFT_HTTP_PORT),
        rate_hz=1200.0,
    )
    client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    client.settimeout(2.0)
    try:
        client.sendto(struct.pack(">HHI", 0x1234, 2, 0), (host, RDT_PORT))
        server.push([[1, 0, 0, 0, 0, 0]])  # the first record: the stream has started
        assert RECORD.unpack(client.recvfrom(64)[0])[3] == 1
        # 600 samples (0.5 s) arrive at once, as after a stall of the cell's process
        server.push([[i, 0, 0, 0, 0, 0] for i in range(2, 602)])
        sequence, ft_sequence, _, fx, *_ = RECORD.unpack(client.recvfrom(64)[0])
        assert sequence == 2
        # not the backlog's oldest: at most 13 ms (3 ms of delay, 10 of lateness) before
        # the newest, 16 samples at 1200 Hz
        assert fx >= 601 - 16
        assert ft_sequence == fx  # the sensor's own count includes the samples not sent
    finally:
        client.close()
        server.close()
