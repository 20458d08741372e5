"""The host side: the transport interface every engine and board link implements
(:mod:`.transport`), the host driver that turns FBG traces into core currents and reads spikes
back (:mod:`.driver`), and recorded-trace loading (:mod:`.traces`)."""
