package model

import pc "platformctrl"

func moveToStation(p *Platform, t pc.Telegram) string {
	return "not implemented yet"
}
