"""The Mapbox Vector Tile 2.1 message classes (`Tile`, its `Layer`, `Feature`, `Value`).

Built with the protobuf library's descriptor APIs from ``vector_tile.desc``, the
``FileDescriptorSet`` that protoc writes for ``vector_tile.proto`` beside it
(``make proto``; protoc from grpcio-tools). Loading the descriptor instead of generated
``_pb2`` code keeps the classes working on any protobuf runtime from 4 on (generated code
is tied to the runtime's major version), and a private descriptor pool keeps them apart
from other vector tile packages (mapbox-vector-tile registers its own
``vector_tile.proto`` in the default pool).
"""

from __future__ import annotations

from importlib.resources import files

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

__all__ = ["Tile", "Layer", "Feature", "Value", "GEOM_TYPE"]

_POOL = descriptor_pool.DescriptorPool()
for _file in descriptor_pb2.FileDescriptorSet.FromString(
        files("rnsca.tiles").joinpath("vector_tile.desc").read_bytes()).file:
    _POOL.Add(_file)

Tile = message_factory.GetMessageClass(_POOL.FindMessageTypeByName("vector_tile.Tile"))
Layer = message_factory.GetMessageClass(_POOL.FindMessageTypeByName("vector_tile.Tile.Layer"))
Feature = message_factory.GetMessageClass(
    _POOL.FindMessageTypeByName("vector_tile.Tile.Feature"))
Value = message_factory.GetMessageClass(_POOL.FindMessageTypeByName("vector_tile.Tile.Value"))

#: The geometry types of a feature (``Tile.GeomType``).
GEOM_TYPE = {"POINT": 1, "LINESTRING": 2, "POLYGON": 3}
