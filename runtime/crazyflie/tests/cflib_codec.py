#!/usr/bin/env python3
"""The cross-check's other side: cflib (Bitcraze's Python library, written independently of
this project) encodes the commands the backend sends and decodes the packets the emulated
Crazyflie sends.

Reads one JSON object on its standard input:
  {"encode": [COMMAND, ...], "decode": [PACKET, ...]}
and prints one JSON object:
  {"encoded": ["HEX", ...], "decoded": [{...}, ...]}

Each COMMAND is {"kind": ..., arguments}; cflib's own call for it builds the packet, which
a stand-in Crazyflie object captures from `send_packet` (header byte and payload, as hex).
cflib has no altHold sender: that packet is cflib's CRTPPacket on the generic commander's
port with the firmware's altHold layout. Each PACKET is {"kind": ..., "hex": ...}: the bytes
go through cflib's own decoder for that kind, and what it understood is printed.
"""
import json
import struct
import sys

from cflib.crazyflie.commander import Commander
from cflib.crazyflie.localization import Localization
from cflib.crazyflie.log import Log, LogConfig, LogTocElement
from cflib.crazyflie.param import Param
from cflib.crazyflie.platformservice import PlatformService
from cflib.crazyflie.supervisor import Supervisor
from cflib.crazyflie.toc import Toc, TocFetcher
from cflib.crtp.crtpstack import CRTPPacket, CRTPPort
from cflib.utils.callbacks import Caller

ALT_HOLD = 4


class Platform:
    def __init__(self, version):
        self.version = version

    def get_protocol_version(self):
        return self.version


class NoCache:
    def fetch(self, crc):
        return None

    def insert(self, crc, toc):
        pass


class StandIn:
    """The parts of cflib's Crazyflie its modules use: it keeps what they send."""

    def __init__(self, version):
        self.sent = []
        self.callbacks = {}
        self.platform = Platform(version)
        self.link = object()
        self.connected = Caller()
        self.disconnected = Caller()
        self.connection_requested = Caller()
        self.fully_connected = Caller()
        self.log = None

    def send_packet(self, pk, expected_reply=(), resend=False, timeout=0.2):
        self.sent.append(bytes([pk.header]) + bytes(pk.data))

    def add_port_callback(self, port, cb):
        self.callbacks.setdefault(port, []).append(cb)

    def remove_port_callback(self, port, cb):
        if cb in self.callbacks.get(port, []):
            self.callbacks[port].remove(cb)


def packet(hexed):
    raw = bytes.fromhex(hexed)
    return CRTPPacket(header=raw[0], data=raw[1:])


def toc_element(ident, kind, complete_name):
    group, name = complete_name.split('.')
    data = bytes([kind]) + group.encode() + b'\0' + name.encode() + b'\0'
    return LogTocElement(ident, data)


def log_with(cf, variables):
    """cflib's Log with a TOC of `variables` ([name, type code, id]), protocol v2."""
    log = Log(cf)
    log._useV2 = True
    log.toc = Toc()
    for name, kind, ident in variables:
        log.toc.add_element(toc_element(ident, kind, name))
    cf.log = log
    return log


def log_config(cf, block, period_ms, variables):
    log = log_with(cf, variables)
    config = LogConfig(name='block%d' % block, period_in_ms=period_ms)
    for name, _, _ in variables:
        config.add_variable(name)
    log._config_id_counter = block
    log.add_config(config)
    return config


def encode(c):
    cf = StandIn(c.get('protocol', 12))
    kind = c['kind']
    if kind == 'alt_hold':
        pk = CRTPPacket()
        pk.port = CRTPPort.COMMANDER_GENERIC
        pk.channel = 0
        pk.data = struct.pack('<Bffff', ALT_HOLD, c['roll'], c['pitch'], c['yawrate'], c['vz'])
        cf.send_packet(pk)
    elif kind == 'stop':
        Commander(cf).send_stop_setpoint()
    elif kind == 'position':
        Commander(cf).send_position_setpoint(c['x'], c['y'], c['z'], c['yaw'])
    elif kind == 'ext_pose':
        Localization(cf).send_extpose(c['pos'], c['quat'])
    elif kind == 'protocol_version':
        # cflib asks for the version once the link service says it is a Crazyflie.
        service = PlatformService(cf)
        service._crt_service_callback(CRTPPacket(header=0xFD, data=b'Bitcraze Crazyflie'))
        cf.sent = cf.sent[-1:]
    elif kind == 'toc_info':
        TocFetcher(cf, LogTocElement, CRTPPort.LOGGING, Toc(), None, NoCache()).start()
    elif kind == 'toc_item':
        fetcher = TocFetcher(cf, LogTocElement, CRTPPort.LOGGING, Toc(), None, NoCache())
        fetcher._useV2 = True
        fetcher._request_toc_element(c['index'])
    elif kind == 'log_reset':
        log_with(cf, [])._send_reset_packet()
    elif kind == 'log_create':
        log_config(cf, c['block'], 10 * c['period_10ms'], c['vars']).create()
    elif kind in ('log_start', 'log_stop', 'log_delete'):
        config = log_config(cf, c['block'], 10 * c['period_10ms'], c['vars'])
        if kind == 'log_start':
            config.added = True
            config.start()
        elif kind == 'log_stop':
            config.stop()
        else:
            config.delete()
    elif kind == 'set_param':
        Param(cf).set_value_raw(c['name'], c['type'], c['value'])
    elif kind == 'arm':
        Supervisor(cf).send_arming_request(c['arm'])
    else:
        raise ValueError('unknown command ' + kind)
    if len(cf.sent) != 1:
        raise ValueError('%s sent %d packets' % (kind, len(cf.sent)))
    return cf.sent[0].hex()


def decode(d):
    cf = StandIn(12)
    kind = d['kind']
    pk = packet(d['hex'])
    if kind == 'version':
        service = PlatformService(cf)
        service._callback = lambda: None
        service._platform_callback(pk)
        return {'version': service.get_protocol_version()}
    if kind in ('toc_info', 'toc_item'):
        toc = Toc()
        fetcher = TocFetcher(cf, LogTocElement, CRTPPort.LOGGING, toc, lambda: None, NoCache())
        fetcher._useV2 = True
        if kind == 'toc_info':
            fetcher.state = 'GET_TOC_INFO'
            fetcher._new_packet_cb(pk)
            return {'count': fetcher.nbr_of_items, 'crc': fetcher._crc}
        fetcher.state = 'GET_TOC_ELEMENT'
        fetcher.requested_index = d['index']
        fetcher.nbr_of_items = d['index'] + 1
        fetcher._new_packet_cb(pk)
        element = toc.get_element_by_id(d['index'])
        return {'group': element.group, 'name': element.name, 'ctype': element.ctype}
    if kind == 'log_data':
        config = log_config(cf, d['block'], 10, d['vars'])
        got = {}
        config.data_received_cb.add_callback(
            lambda ts, data, conf: got.update({'timestamp': ts, 'data': data}))
        cf.log._new_packet_cb(pk)
        return got
    if kind == 'log_ack':
        config = log_config(cf, d['block'], 10, d['vars'])
        config.pending = True
        cf.log._new_packet_cb(pk)
        return {'added': config.added, 'started': config.started, 'sent': [s.hex() for s in cf.sent]}
    raise ValueError('unknown packet ' + kind)


def main():
    request = json.load(sys.stdin)
    out = {
        'encoded': [encode(c) for c in request.get('encode', [])],
        'decoded': [decode(d) for d in request.get('decode', [])],
    }
    print(json.dumps(out))


if __name__ == '__main__':
    main()
