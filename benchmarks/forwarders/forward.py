"""Python forwarder, two blocking threads (see __init__.py): ``python forward.py TARGET_PORT``. Loopback only."""

import contextlib
import socket
import sys
import threading


def pump(src: socket.socket, dst: socket.socket) -> None:
    with contextlib.suppress(OSError):
        while data := src.recv(65536):
            dst.sendall(data)
    with contextlib.suppress(OSError):
        dst.shutdown(socket.SHUT_WR)  # pass the FIN (or the end after a reset) on


def main(target: int) -> None:
    listener = socket.create_server(("127.0.0.1", 0))
    print(f"proxy listening at 127.0.0.1:{listener.getsockname()[1]}", flush=True)
    while True:
        client, _ = listener.accept()
        with client, contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", target)) as server:
            for sock in (client, server):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            threads = [threading.Thread(target=pump, args=pair) for pair in ((client, server), (server, client))]
            for thread in threads:
                thread.start()
            for thread in threads:
                thread.join()


if __name__ == "__main__":
    main(int(sys.argv[1]))
