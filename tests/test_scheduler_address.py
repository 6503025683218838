"""``--scheduler ADDRESS``: checked before any work, then probed under one deadline for the
connection, distributed's handshake and the scheduler's reply (issue 31, class 8).

Small servers in threads stand in for the unlucky addresses: a port that accepts and never
answers (``Client(address, timeout=...)`` alone waits for ever in the handshake), one that
answers garbage (distributed read a frame length of exabytes: MemoryError, exit 3)."""

import socket
import threading
import time

import pytest

from scatterbench.validation.cli import main
from scatterbench.validation.fitting import executors
from scatterbench.validation.fitting.executors import DaskExecutor, SchedulerError
from scatterbench.validation.fitting.scheduler import check_scheduler_address

DEADLINE = 2.0


def _server(reply):
    """A listening socket on a free local port; each connection gets ``reply`` (``None``:
    nothing, ever).  Returns the port; the server stops with the test process."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(8)
    held = []

    def serve():
        while True:
            conn, _ = srv.accept()
            held.append(conn)  # kept open: the peer sees no close, only silence or garbage
            if reply is not None:
                conn.sendall(reply)

    threading.Thread(target=serve, daemon=True).start()
    return srv.getsockname()[1]


@pytest.mark.parametrize(
    "reply, said",
    [
        (None, "no dask.distributed scheduler answered within 2 s"),
        # a frame length of 2^64 - 1 bytes, then noise: what a wrong service's banner looks like
        (b"\xff" * 64, "something answered, but not a dask.distributed scheduler"),
        (b"\x00\x00\x00\x00\x00\x00\x00\x7f" + b"HTTP/1.1 400 Bad Request\r\n" * 4, "not a dask.distributed"),
    ],
    ids=["silent", "garbage", "huge-frame"],
)
def test_a_port_that_does_not_answer_as_a_scheduler_is_refused_within_the_deadline(reply, said):
    port = _server(reply)
    t = time.monotonic()
    with pytest.raises(SchedulerError) as exc:
        DaskExecutor(f"tcp://127.0.0.1:{port}", timeout=DEADLINE)
    assert time.monotonic() - t < DEADLINE + 3.0  # one deadline, plus the cancellation's margin
    assert said in str(exc.value) and f"127.0.0.1:{port}" in str(exc.value)


@pytest.mark.parametrize(
    "address, reason",
    [
        ("foo://10.0.0.5:8786", "unknown protocol foo://"),
        ("inproc://10.0.0.5:8786", "inproc:// connects only within one Python process"),
        ("tls://10.0.0.5:8786", "tls:// needs certificates"),
        ("tcp://10.0.0.5:0", "port 0 is outside 1-65535"),
        ("tcp://10.0.0.5:65536", "port 65536 is outside 1-65535"),
        ("tcp://:8786", "no host"),
        ("tcp://10.0.0.5", "no port"),
        ("tcp://a b:8786", "not HOST:PORT"),
    ],
)
def test_an_address_no_scheduler_can_be_at_is_refused_before_anything_is_sent(address, reason, monkeypatch):
    monkeypatch.delenv("DASK_DISTRIBUTED__COMM__TLS__CA_FILE", raising=False)
    with pytest.raises(SchedulerError, match=reason):
        check_scheduler_address(address)


def test_addresses_a_scheduler_can_be_at_are_accepted():
    assert check_scheduler_address("10.0.0.5:8786") == "tcp://10.0.0.5:8786"
    assert check_scheduler_address("TCP://host.example:8786") == "tcp://host.example:8786"
    assert check_scheduler_address("tcp://[::1]:8786") == "tcp://[::1]:8786"


def test_tls_with_certificates_configured_is_accepted(tmp_path):
    import dask.config

    ca, cert = tmp_path / "ca.pem", tmp_path / "client.pem"
    ca.write_text("x")
    cert.write_text("x")
    conf = {"distributed.comm.tls.ca-file": str(ca), "distributed.comm.tls.client.cert": str(cert)}
    with dask.config.set(conf):
        assert check_scheduler_address("tls://10.0.0.5:8786") == "tls://10.0.0.5:8786"
    with dask.config.set({**conf, "distributed.comm.tls.ca-file": str(tmp_path / "gone.pem")}):
        with pytest.raises(SchedulerError, match="gone.pem'?: no such file"):
            check_scheduler_address("tls://10.0.0.5:8786")


def test_a_privileged_port_where_nothing_listens_is_refused_at_once():
    t = time.monotonic()
    with pytest.raises(SchedulerError, match="port 1 is a privileged port .* nothing listens there"):
        DaskExecutor("tcp://127.0.0.1:1", timeout=30)
    assert time.monotonic() - t < 5.0  # not the 30 s deadline: nothing to wait for


@pytest.mark.parametrize(
    "command", [["report", "--quick"], ["validate", "--quick"], ["stability", "--no-energy"]]
)
@pytest.mark.parametrize(
    "address, reason",
    [("foo://h:1", "unknown protocol foo://"), ("inproc://h:1", "inproc://"), ("tcp://h:0", "port 0")],
)
def test_the_commands_refuse_a_bad_address_with_exit_2(command, address, reason, tmp_path, capsys):
    argv = [*command, "--scheduler", address]
    if command[0] == "report":
        argv += ["--out", str(tmp_path / "r")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"error: --scheduler {address!r}: {reason}" in err and "internal" not in err
    assert not (tmp_path / "r").exists()


def test_the_commands_refuse_a_silent_port_with_exit_2_within_the_deadline(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(executors, "SCHEDULER_TIMEOUT", DEADLINE)
    port = _server(None)
    t = time.monotonic()
    assert main(["report", "--quick", "--out", str(tmp_path / "r"), "--scheduler", f"127.0.0.1:{port}"]) == 2
    assert time.monotonic() - t < DEADLINE + 10.0  # dask's import, then one deadline
    err = capsys.readouterr().err
    assert "no dask.distributed scheduler answered within 2 s" in err and "internal" not in err


def test_workers_and_scheduler_together_are_refused(capsys):
    assert main(["validate", "--quick", "--workers", "2", "--scheduler", "tcp://h:8786"]) == 2
    assert "--workers and --scheduler: give one" in capsys.readouterr().err
