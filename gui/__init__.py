"""PlatformCtrlGUI in the browser (guide chapter 5): the gateway (Python) and the web application (gui/web)."""
