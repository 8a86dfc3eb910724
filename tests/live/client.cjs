// An independent client of the live view: Foxglove's own WebSocket protocol client
// (@foxglove/ws-protocol) subscribes to every channel the server advertises, and Foxglove's
// ROS 2 message reader (@foxglove/rosmsg + @foxglove/rosmsg2-serialization) decodes each CDR
// message against the schema text advertised with its channel; JSON messages are parsed.
//
// node client.cjs ws://HOST:PORT OUT.json TIMEOUT_S
//
// Connects (retrying until the server is up), collects until the server closes the
// connection or TIMEOUT_S passes, and writes OUT.json: the channels as advertised, and per
// message its topic, log time (ns), the SHA-256 of its bytes, and the decoded fields the test
// checks (`t_s`, and `position_m` on /reference).
"use strict";
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");
const WebSocket = require("ws");
const crypto = require("crypto");
const fs = require("fs");

const [url, outPath, timeoutArg] = process.argv.slice(2);
const deadline = Date.now() + 1000 * Number(timeoutArg || 120);

const channels = [];
const bySubscription = new Map();
const messages = [];
const errors = [];
let finished = false;

function finish(reason) {
  if (finished) return;
  finished = true;
  fs.writeFileSync(outPath, JSON.stringify({ reason, channels, messages, errors }));
  process.exit(0);
}

function decoderFor(channel) {
  if (channel.encoding === "cdr") {
    if (channel.schemaEncoding !== "ros2msg") {
      throw new Error(`${channel.topic}: CDR under schema encoding ${channel.schemaEncoding}`);
    }
    const reader = new MessageReader(parse(channel.schema, { ros2: true }));
    return (bytes) => reader.readMessage(bytes);
  }
  if (channel.encoding === "json") {
    const text = new TextDecoder("utf-8", { fatal: true });
    return (bytes) => JSON.parse(text.decode(bytes));
  }
  throw new Error(`${channel.topic}: unknown message encoding ${channel.encoding}`);
}

function connect() {
  if (Date.now() > deadline) finish("no connection before the timeout");
  // The SDK's server speaks the protocol under the subprotocol name `foxglove.sdk.v1`.
  const ws = new WebSocket(url, ["foxglove.sdk.v1", FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  let opened = false;
  ws.on("error", () => {
    if (!opened) setTimeout(connect, 50);
  });
  ws.on("open", () => {
    opened = true;
  });
  const client = new FoxgloveClient({ ws });
  client.on("advertise", (advertised) => {
    for (const c of advertised) {
      channels.push({
        id: c.id,
        topic: c.topic,
        encoding: c.encoding,
        schemaName: c.schemaName,
        schemaEncoding: c.schemaEncoding,
        schema: c.schema,
      });
      try {
        const decode = decoderFor(c);
        bySubscription.set(client.subscribe(c.id), { topic: c.topic, decode });
      } catch (e) {
        errors.push(String(e));
      }
    }
  });
  client.on("message", ({ subscriptionId, timestamp, data }) => {
    const sub = bySubscription.get(subscriptionId);
    if (!sub) {
      errors.push(`a message on unknown subscription ${subscriptionId}`);
      return;
    }
    const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
    const record = {
      topic: sub.topic,
      log_time: timestamp.toString(),
      sha256: crypto.createHash("sha256").update(bytes).digest("hex"),
    };
    try {
      const m = sub.decode(bytes);
      if (typeof m.t_s === "number") record.t_s = m.t_s;
      if (sub.topic === "/reference") record.position_m = Array.from(m.position_m);
      if (sub.topic === "/events") record.kind = m.kind;
    } catch (e) {
      errors.push(`${sub.topic}: ${e}`);
    }
    messages.push(record);
  });
  ws.on("close", () => {
    if (opened) finish("closed by the server");
  });
}

setTimeout(() => finish("timeout"), Math.max(0, deadline - Date.now()));
connect();
