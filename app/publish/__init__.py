"""The station seen from other programs: an OPC UA server (asyncua) and an MQTT Sparkplug B
publisher (paho-mqtt), both fed from the station's `Readings` without the scan waiting for them
(docs/architecture.md section 1). Neither writes memory or checks a role itself: what a client
asks is a command of the station's command layer (app/authority/), checked and journaled there."""
