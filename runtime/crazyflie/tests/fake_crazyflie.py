#!/usr/bin/env python3
"""A fake Crazyflie on cflib's UDP link (cflib.crtp.udpdriver.UdpDriver, its packets
cflib.crtp.crtpstack.CRTPPacket), for the backend's tests over UDP loopback.

    fake_crazyflie.py BACKEND_PORT PROTOCOL [no-auto-arm]

It connects cflib's UDP driver to the backend's port on 127.0.0.1 and prints its own port
first, {"port": N}. It answers as a Crazyflie's firmware does:
- the protocol version (PROTOCOL) on the platform port;
- the log TOC (v2): 40 other variables and the ones the backend logs, in a shuffled order;
  log blocks created, started, stopped, deleted and reset, each answered [cmd, block, errno];
  samples of the started blocks at their periods, packed with cflib's log type table;
- parameter writes by name (stabilizer.estimator, kalman.resetEstimation), answered with
  the errno (ENOENT for others, EINVAL for a wrong type);
- set-points (altHold, position, stop) and external poses, which move its state: the
  estimate takes the external pose's x, y and yaw; z follows the altHold climb rate while
  the motors run, the pose's z while they stand.
Each packet received prints as {"rx": HEX, "port": P, "channel": C}, the set-points and
poses with their values, {"kind": ..., "values": [...]}. Lines on its standard input:
"lock" (the supervisor locks), "battery_low", "console TEXT", "quiet" (no more samples);
it ends when its standard input closes.
"""
import json
import math
import os
import random
import select
import struct
import sys
import time

from cflib.crazyflie.log import LogTocElement
from cflib.crtp.crtpstack import CRTPPacket
from cflib.crtp.udpdriver import UdpDriver

ENOENT, EINVAL = 2, 22
LOGGED = [
    ('stateEstimate.x', 7), ('stateEstimate.y', 7), ('stateEstimate.z', 7),
    ('stabilizer.roll', 7), ('stabilizer.pitch', 7), ('stabilizer.yaw', 7),
    ('pm.vbat', 7), ('pm.batteryLevel', 1), ('pm.state', 4), ('supervisor.info', 2),
]
PARAMS = {'stabilizer.estimator': (0x08, 1), 'kalman.resetEstimation': (0x08, 0)}


class Fake:
    def __init__(self, driver, protocol, auto_arm):
        self.driver = driver
        self.protocol = protocol
        rng = random.Random(7)
        toc = [('filler.v%d' % i, rng.choice([1, 2, 3, 4, 5, 6, 7])) for i in range(40)]
        toc += LOGGED
        rng.shuffle(toc)
        self.toc = toc
        self.values = {name: 0.0 for name, _ in toc}
        self.values.update({'pm.vbat': 3.9, 'pm.batteryLevel': 80, 'pm.state': 0})
        self.params = dict(PARAMS)
        self.blocks = {}
        self.auto_arm = auto_arm
        self.armed = False
        self.locked = False
        self.motors = False
        self.vz = 0.0
        self.target_z = None
        self.quiet = False
        self.last = time.monotonic()

    def send(self, port, channel, data):
        pk = CRTPPacket()
        pk.set_header(port, channel)
        pk.data = bytes(data)
        self.driver.send_packet(pk)

    def received(self, pk):
        raw = bytes([pk.header]) + bytes(pk.data)
        out = {'rx': raw.hex(), 'port': pk.port, 'channel': pk.channel}
        data = bytes(pk.data)
        handler = {
            (13, 1): self.platform_version, (13, 0): self.arm_legacy, (9, 1): self.arm,
            (5, 0): self.toc_request, (5, 1): self.log_setting, (2, 3): self.param,
            (7, 0): self.setpoint, (6, 1): self.localization,
        }.get((pk.port, pk.channel))
        if handler and data:
            extra = handler(data)
            if extra:
                out.update(extra)
        print(json.dumps(out), flush=True)

    def platform_version(self, data):
        if data[0] == 0:
            self.send(13, 1, struct.pack('<Bi', 0, self.protocol))

    def arm_legacy(self, data):
        if data[0] == 1 and len(data) == 2:
            self.armed = bool(data[1])
            return {'kind': 'arm', 'values': [data[1]]}

    def arm(self, data):
        if data[0] == 1 and len(data) == 2:
            self.armed = bool(data[1])
            return {'kind': 'arm', 'values': [data[1]]}

    def toc_request(self, data):
        if data[0] == 3:
            self.send(5, 0, struct.pack('<BHIBB', 3, len(self.toc), 0xC0FFEE, 16, 128))
        elif data[0] == 2 and len(data) == 3:
            index = struct.unpack('<H', data[1:3])[0]
            if index >= len(self.toc):
                self.send(5, 0, [2])
                return
            name, kind = self.toc[index]
            group, var = name.split('.')
            self.send(5, 0, struct.pack('<BHB', 2, index, kind) + group.encode() + b'\0' +
                      var.encode() + b'\0')

    def log_setting(self, data):
        cmd, block = data[0], data[1] if len(data) > 1 else 0
        error = 0
        if cmd == 5:
            self.blocks = {}
        elif cmd == 6:
            ops = [struct.unpack('<BH', data[i:i + 3]) for i in range(2, len(data), 3)]
            if block in self.blocks:
                error = 17
            elif any(ident >= len(self.toc) for _, ident in ops):
                error = ENOENT
            else:
                self.blocks[block] = {'ops': ops, 'period': 0, 'next': 0.0}
        elif cmd == 3:
            if block in self.blocks:
                self.blocks[block]['period'] = data[2] * 0.01
            else:
                error = ENOENT
        elif cmd in (2, 4):
            if block in self.blocks and cmd == 2:
                del self.blocks[block]
            elif block in self.blocks:
                self.blocks[block]['period'] = 0
            else:
                error = ENOENT
        self.send(5, 1, [cmd, block, error])
        return {'kind': 'log', 'values': [cmd, block, error]}

    def param(self, data):
        if data[0] != 0:
            return
        group, name, rest = data[1:].split(b'\0', 2)
        full = group.decode() + '.' + name.decode()
        kind, value = rest[0], rest[1:]
        error = 0
        if full not in self.params:
            error = ENOENT
        elif self.params[full][0] != kind:
            error = EINVAL
        else:
            self.params[full] = (kind, value[0])
        self.send(2, 3, [0] + list(group) + [0] + list(name) + [0, error])
        return {'kind': 'param', 'values': [full, value[0], error]}

    def setpoint(self, data):
        kind = data[0]
        if self.locked:
            return {'kind': 'ignored'}
        if kind == 4 and len(data) == 17:
            values = list(struct.unpack('<ffff', data[1:]))
            self.motors = True
            self.vz, self.target_z = values[3], None
            return {'kind': 'alt_hold', 'values': values}
        if kind == 7 and len(data) == 17:
            values = list(struct.unpack('<ffff', data[1:]))
            self.motors = True
            self.vz, self.target_z = 0.0, values[2]
            return {'kind': 'position', 'values': values}
        if kind == 0 and len(data) == 1:
            self.motors = False
            self.vz = 0.0
            return {'kind': 'stop', 'values': []}

    def localization(self, data):
        if data[0] == 8 and len(data) == 29:
            x, y, z, qx, qy, qz, qw = struct.unpack('<7f', data[1:])
            self.values['stateEstimate.x'] = x
            self.values['stateEstimate.y'] = y
            if not self.motors:
                self.values['stateEstimate.z'] = z
            yaw = math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
            self.values['stabilizer.yaw'] = math.degrees(yaw)
            return {'kind': 'ext_pose', 'values': [x, y, z, qx, qy, qz, qw]}

    def command(self, line):
        word, _, rest = line.strip().partition(' ')
        if word == 'lock':
            self.locked, self.motors = True, False
        elif word == 'battery_low':
            self.values.update({'pm.vbat': 3.1, 'pm.batteryLevel': 5, 'pm.state': 3})
        elif word == 'console':
            text = (rest + '\n').encode()
            for i in range(0, len(text), 30):
                self.send(0, 0, text[i:i + 30])
        elif word == 'quiet':
            self.quiet = True

    def tick(self):
        now = time.monotonic()
        dt, self.last = now - self.last, now
        z = self.values['stateEstimate.z']
        if self.motors and self.target_z is None:
            z = max(0.0, z + self.vz * dt)
        elif self.motors:
            z += max(-0.5 * dt, min(0.5 * dt, self.target_z - z))
        self.values['stateEstimate.z'] = z
        info = 1 | 8
        info |= 4 if self.auto_arm else 0
        info |= 2 if self.armed or (self.auto_arm and self.motors) else 0
        info |= 16 if self.motors and z > 0.02 else 0
        info |= 64 if self.locked else 0
        self.values['supervisor.info'] = info
        if self.quiet:
            return
        for block, b in self.blocks.items():
            if b['period'] <= 0 or now < b['next']:
                continue
            b['next'] = now + b['period']
            payload = b''
            for byte, ident in b['ops']:
                name, _ = self.toc[ident]
                fmt = LogTocElement.get_unpack_string_from_id(byte & 0x0F)
                value = self.values[name]
                payload += struct.pack(fmt, value if fmt in ('<f', '<e') else int(value))
            millis = int(now * 1000) & 0xFFFFFF
            self.send(5, 2, bytes([block]) + millis.to_bytes(3, 'little') + payload)


def main():
    backend, protocol = int(sys.argv[1]), int(sys.argv[2])
    auto_arm = 'no-auto-arm' not in sys.argv[3:]
    driver = UdpDriver()
    driver.connect('udp://127.0.0.1:%d' % backend, None, lambda e: None)
    print(json.dumps({'port': driver.socket.getsockname()[1]}), flush=True)
    fake = Fake(driver, protocol, auto_arm)
    while True:
        pk = driver.receive_packet(0.002)
        while pk is not None:
            fake.received(pk)
            pk = driver.receive_packet(0)
        fake.tick()
        if select.select([sys.stdin], [], [], 0)[0]:
            line = sys.stdin.readline()
            if not line:
                driver.close()
                return
            fake.command(line)


if __name__ == '__main__':
    os.environ.setdefault('PYTHONUNBUFFERED', '1')
    main()
