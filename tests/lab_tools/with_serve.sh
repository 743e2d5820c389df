#!/usr/bin/env bash
# with_serve.sh MAGLEV_HIL WORKDIR COMMAND...
# Starts `maglev-hil serve` on a free 127.0.0.1 port (flash in WORKDIR), waits
# until it listens, runs COMMAND with MAGLEV_TCP=127.0.0.1:PORT in its
# environment, stops the server (SIGTERM) and exits with COMMAND's status
# (or 1 when the server did not come up or did not stop cleanly). The
# server's log is printed when anything failed.
set -u
HIL=$1; WORK=$2; shift 2
rm -rf "$WORK"; mkdir -p "$WORK"
PORT=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"$HIL" serve --modbus-tcp "127.0.0.1:$PORT" --flash "$WORK/flash.bin" >"$WORK/serve.log" 2>&1 &
HIL_PID=$!
cleanup() { kill "$HIL_PID" 2>/dev/null; wait "$HIL_PID" 2>/dev/null; }
trap cleanup EXIT
up=0
for _ in $(seq 100); do
  if grep -q "listening on 127.0.0.1:$PORT" "$WORK/serve.log"; then up=1; break; fi
  kill -0 "$HIL_PID" 2>/dev/null || break
  sleep 0.1
done
if [ "$up" != 1 ]; then
  echo "with_serve.sh: maglev-hil serve did not come up on 127.0.0.1:$PORT"; cat "$WORK/serve.log"; exit 1
fi
MAGLEV_TCP="127.0.0.1:$PORT" "$@"; rc=$?
kill -TERM "$HIL_PID"; wait "$HIL_PID"; src=$?; trap - EXIT
if [ "$rc" -ne 0 ] || [ "$src" -ne 0 ]; then
  echo "---- maglev-hil serve log (server exit $src) ----"; cat "$WORK/serve.log"
fi
[ "$rc" -eq 0 ] && [ "$src" -eq 0 ]
