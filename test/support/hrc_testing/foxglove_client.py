"""A client of the Foxglove WebSocket protocol for the tests and benches (``websockets``).

It subscribes to every channel a server advertises and hands each message over decoded: JSON
channels as Python values, protobuf channels (the SDK's typed messages) with the schema the
server advertised. The SDK names its protocol ``foxglove.sdk.v1`` (ws-protocol v1).
"""

import asyncio
import base64
import json
import struct

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
import websockets

SUBPROTOCOL = 'foxglove.sdk.v1'
MESSAGE_DATA = 0x01             # binary opcode: subscription id (u32), log time (u64), payload


def decoder_of(channel: dict):
    """Return a function of a payload for an advertised channel (JSON or protobuf)."""
    if channel['encoding'] == 'json':
        return json.loads
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel['schema']))
    pool = descriptor_pool.DescriptorPool()
    for file in files.file:
        pool.Add(file)
    return message_factory.GetMessageClass(
        pool.FindMessageTypeByName(channel['schemaName'])).FromString


async def follow(url: str, on_message, done, retry_s: float = 0.2) -> dict:
    """Subscribe to all and call ``on_message(topic, decoded, size)`` until ``done()``.

    Connects again (every ``retry_s``) while the server is not up yet or went away; returns
    the channels advertised ({topic: channel}).
    """
    channels = {}
    while not done():
        try:
            async with websockets.connect(url, subprotocols=[SUBPROTOCOL]) as client:
                by_id, decoders = {}, {}
                while not done():
                    try:
                        frame = await asyncio.wait_for(client.recv(), 0.5)
                    except asyncio.TimeoutError:
                        continue
                    if isinstance(frame, str):
                        message = json.loads(frame)
                        if message.get('op') == 'advertise':
                            for channel in message['channels']:
                                by_id[channel['id']] = channel
                                decoders[channel['id']] = decoder_of(channel)
                                channels[channel['topic']] = channel
                            await client.send(json.dumps({'op': 'subscribe', 'subscriptions': [
                                {'id': channel['id'], 'channelId': channel['id']}
                                for channel in message['channels']]}))
                    elif frame[0] == MESSAGE_DATA:
                        (subscription,) = struct.unpack_from('<I', frame, 1)
                        on_message(by_id[subscription]['topic'],
                                   decoders[subscription](frame[13:]), len(frame))
        except (OSError, websockets.exceptions.WebSocketException):
            await asyncio.sleep(retry_s)
    return channels
