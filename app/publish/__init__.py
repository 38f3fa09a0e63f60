"""The station seen from other programs: an OPC UA server (asyncua) and an MQTT Sparkplug B
publisher (paho-mqtt), both fed from the engine's snapshots without the scan waiting for them
(docs/architecture.md section 1). Neither writes memory itself: their writes enter the engine's
queue and are journaled like an operator's."""
