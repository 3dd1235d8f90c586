"""cutproxy.py TARGET_PORT NBYTES [DELAY] - a TCP proxy on a free loopback port (printed on the
first line of stdout) to 127.0.0.1:TARGET_PORT that closes each connection once NBYTES of the
answer have gone through (0: never), a download cut mid-transfer for
tests/clients/test_python_client.sh; and holds each answer DELAY seconds before passing it on
(an answer still on its way when a client is interrupted, for tests/clients/test_sweep.sh)."""

import socket
import sys
import threading
import time

target, limit = int(sys.argv[1]), int(sys.argv[2])
delay = float(sys.argv[3]) if len(sys.argv) > 3 else 0.0


def pipe(src, dst, cut, hold=0.0):
    sent = 0
    try:
        while True:
            data = src.recv(65536)
            if not data:
                break
            if hold and sent == 0:
                time.sleep(hold)
            if cut and sent + len(data) >= cut:
                dst.sendall(data[:cut - sent])
                break
            dst.sendall(data)
            sent += len(data)
    except OSError:
        pass
    for s in (src, dst):
        try:
            s.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass


server = socket.socket()
server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
server.bind(("127.0.0.1", 0))
server.listen(5)
print(server.getsockname()[1], flush=True)
while True:
    client, _ = server.accept()
    upstream = socket.create_connection(("127.0.0.1", target))
    threading.Thread(target=pipe, args=(client, upstream, 0), daemon=True).start()
    threading.Thread(target=pipe, args=(upstream, client, limit, delay), daemon=True).start()
