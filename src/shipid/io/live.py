"""Live feeds over UDP and TCP: a listener that binds only the address it is given, and a sender.

:class:`Listener` (``udp://HOST:PORT`` or ``tcp://HOST:PORT``) yields ``(line, receive_time)`` for every
text line that arrives: a UDP datagram may hold several lines; a TCP stream is split at newlines (one client
at a time; when it closes, the next is accepted). What cannot be used is counted in :attr:`Listener.counts`
and dropped, never raised: a datagram longer than ``max_datagram`` bytes, a TCP line longer than
``max_line``, bytes that are not ASCII, UDP datagrams beyond ``max_rate`` per second (a flood), and
datagrams that arrive while ``max_queue`` already wait (the socket is read by a thread of its own, so a long
update never leaves datagrams to overflow the kernel's buffer). A TCP sender is slowed down instead (the
reader waits for room in the queue, and TCP's flow control does the rest).
The host must be given (``0.0.0.0`` binds every interface only when asked for in so many words).

:class:`Sender` writes lines to ``udp://`` (one datagram per call) or ``tcp://`` (a connection).
"""

from __future__ import annotations

import queue
import select
import socket
import threading
import time
from urllib.parse import urlsplit

from shipid.errors import InputError

MAX_DATAGRAM = 2048
MAX_LINE = 512
MAX_RATE = 20000.0
MAX_QUEUE = 100_000          # reads waiting for the monitor (UDP: the newest beyond are dropped; TCP: waits)


def parse_url(url: str) -> tuple[str, str, int]:
    """``(scheme, host, port)`` of ``udp://HOST:PORT`` or ``tcp://HOST:PORT``; InputError otherwise."""
    u = urlsplit(url)
    if u.scheme not in ("udp", "tcp"):
        raise InputError(f"'{url}': the address must be udp://HOST:PORT or tcp://HOST:PORT")
    try:
        port = u.port
    except ValueError:
        port = None
    if not u.hostname or port is None or u.path not in ("", "/"):
        raise InputError(f"'{url}': give the host and the port, as udp://127.0.0.1:10110")
    return u.scheme, u.hostname, port


class Listener:
    """Bind ``url`` and read lines from it (see the module docstring). Use as a context manager."""

    def __init__(self, url: str, *, max_datagram: int = MAX_DATAGRAM, max_line: int = MAX_LINE,
                 max_rate: float = MAX_RATE, max_queue: int = MAX_QUEUE):
        self.scheme, host, port = parse_url(url)
        self.max_datagram, self.max_line, self.max_rate = max_datagram, max_line, max_rate
        self.counts = {"datagrams": 0, "lines": 0, "oversized": 0, "not_text": 0, "flood": 0, "empty": 0,
                       "overflow": 0, "connections": 0}
        fam = socket.AF_INET6 if ":" in host else socket.AF_INET
        kind = socket.SOCK_DGRAM if self.scheme == "udp" else socket.SOCK_STREAM
        self.sock = socket.socket(fam, kind)
        try:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            if self.scheme == "udp":
                self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
            self.sock.bind((host, port))
            if self.scheme == "tcp":
                self.sock.listen(1)
        except OSError as err:
            self.sock.close()
            raise InputError(f"cannot listen on {url}: {err.strerror or err}") from None
        self.address = self.sock.getsockname()[:2]
        self.client: socket.socket | None = None
        self._buf = b""
        self._skip = False          # discarding the rest of an oversized TCP line
        self._sec, self._in_sec = -1, 0
        self.max_queue = max_queue
        self._q: queue.Queue = queue.Queue(maxsize=max_queue)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        for s in (self.client, self.sock):
            if s is not None:
                s.close()
        self.client = None

    def _rate_ok(self, now: float) -> bool:
        sec = int(now)
        if sec != self._sec:
            self._sec, self._in_sec = sec, 0
        self._in_sec += 1
        if self._in_sec > self.max_rate:
            self.counts["flood"] += 1
            return False
        return True

    def _text(self, data: bytes) -> list[str] | None:
        try:
            text = data.decode("ascii")
        except UnicodeDecodeError:
            self.counts["not_text"] += 1
            return None
        return [ln for ln in text.replace("\r", "\n").split("\n") if ln.strip()]

    def _reader(self) -> None:
        """The socket read in a thread of its own, so that a long computation never leaves datagrams to the
        kernel's buffer: what arrives goes to a queue (at most ``max_queue``; beyond, counted as overflow)."""
        while not self._stop.is_set():
            try:
                socks = [self.sock] if self.client is None else [self.client]
                ready, _, _ = select.select(socks, [], [], 0.1)
                if not ready:
                    continue
                now = time.time()
                if self.scheme == "udp":
                    self._put((self.sock.recv(65536), now))
                    continue
                if self.client is None:
                    self.client, _ = self.sock.accept()
                    self.counts["connections"] += 1
                    continue
                try:
                    data = self.client.recv(65536)
                except OSError:
                    data = b""
                if not data:
                    self.client.close()
                    self.client = None
                    self._put((None, now))      # end of this connection: a partial line is dropped
                    continue
                self._put((data, now))
            except (OSError, ValueError):       # the socket was closed under us
                return

    def _put(self, item) -> None:
        if self.scheme == "tcp":            # back-pressure: TCP's flow control slows the sender down
            while not self._stop.is_set():
                try:
                    self._q.put(item, timeout=0.2)
                    return
                except queue.Full:
                    continue
            return
        try:
            self._q.put_nowait(item)
        except queue.Full:
            self.counts["overflow"] += 1

    def lines(self, idle_timeout: float | None = None, poll: float = 0.2):
        """Yield ``(line, receive_time, unit)``, ``unit`` the number of the datagram (UDP) or line (TCP) it came
        in; end after ``idle_timeout`` s without data once data have come (never, when None). ``(None, now,
        None)`` is yielded every ``poll`` s of silence (a chance to act on a timer)."""
        if self._thread is None:
            self._thread = threading.Thread(target=self._reader, name="shipid-listener", daemon=True)
            self._thread.start()
        last = None
        while True:
            try:
                data, now = self._q.get(timeout=poll)
            except queue.Empty:
                if idle_timeout is not None and last is not None and time.monotonic() - last > idle_timeout:
                    return
                yield None, time.time(), None
                continue
            last = time.monotonic()
            if self.scheme == "udp":
                self.counts["datagrams"] += 1
                if len(data) > self.max_datagram:
                    self.counts["oversized"] += 1
                    continue
                if not self._rate_ok(now):
                    continue
                lines = self._text(data)
                if lines == []:
                    self.counts["empty"] += 1
                for ln in lines or ():
                    self.counts["lines"] += 1
                    yield ln, now, self.counts["datagrams"]
                continue
            if data is None:
                self._buf, self._skip = b"", False
                continue
            self._buf += data
            while True:
                i = self._buf.find(b"\n")
                if i < 0:
                    if len(self._buf) > self.max_line:
                        self.counts["oversized"] += 1
                        self._buf, self._skip = b"", True
                    break
                raw, self._buf = self._buf[:i], self._buf[i + 1:]
                if self._skip:
                    self._skip = False
                    continue
                self.counts["datagrams"] += 1
                if len(raw) > self.max_line:
                    self.counts["oversized"] += 1
                    continue
                for ln in self._text(raw) or ():
                    self.counts["lines"] += 1
                    yield ln, now, self.counts["datagrams"]


class Sender:
    """Send text to ``udp://HOST:PORT`` (one datagram per :meth:`send`) or ``tcp://HOST:PORT``."""

    def __init__(self, url: str):
        self.scheme, host, port = parse_url(url)
        fam = socket.AF_INET6 if ":" in host else socket.AF_INET
        try:
            if self.scheme == "udp":
                self.sock = socket.socket(fam, socket.SOCK_DGRAM)
                self.sock.connect((host, port))
            else:
                self.sock = socket.create_connection((host, port), timeout=10)
        except OSError as err:
            raise InputError(f"cannot send to {url}: {err.strerror or err}") from None

    def send(self, lines: list[str]) -> None:
        data = ("\r\n".join(lines) + "\r\n").encode("ascii")
        try:
            if self.scheme == "udp":
                self.sock.send(data)
            else:
                self.sock.sendall(data)
        except ConnectionRefusedError:      # UDP: nobody listening (yet); the datagram is lost, as on a network
            pass

    def close(self) -> None:
        self.sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


__all__ = ["Listener", "Sender", "parse_url", "MAX_DATAGRAM", "MAX_LINE"]
