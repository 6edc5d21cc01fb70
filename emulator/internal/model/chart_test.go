package model

import (
	"testing"

	pc "platformctrl"
)

// TestRefusedCommandsChangeNothing: a chart command the table does not allow leaves state, mode and motion
// as they were (E-SRV-018), and an allowed one gives no reply (E-CMD-013).
func TestRefusedCommandsChangeNothing(t *testing.T) {
	p := New(Options{})
	for _, r := range []pc.Telegram{&pc.ConnectToPltfRequest{}, &pc.InitPltfRequest{},
		&pc.SetModeRequest{Mode: pc.ModeMotionVel}, &pc.StartRequest{}, &pc.MoveVelRequest{VelTrans: 100}} {
		if res := p.Handle(r, 1); res.Reply != nil || res.Close || res.Exit {
			t.Fatalf("%s: %+v", r.TelegramName(), res)
		}
	}
	for _, r := range []pc.Telegram{&pc.StartRequest{}, &pc.ContinueRequest{}, &pc.ConnectToPltfRequest{},
		&pc.InitPltfRequest{}, &pc.SetModeRequest{Mode: pc.ModeMotionNo}} {
		p.Handle(r, 2)
		if p.State != Running || p.Mode != pc.ModeMotionVel {
			t.Fatalf("%s in running: now %s, mode %d", r.TelegramName(), p.State, p.Mode)
		}
	}
	p.Advance(3)
	if p.Drive.Pose.X != 200 {
		t.Fatalf("the velocity command was disturbed: x %v", p.Drive.Pose.X)
	}
}

func TestEveryStateHasAReport(t *testing.T) {
	want := map[State]pc.OperationState{NotConnected: 3, Connected: 3, Ready: 0, Running: 1, Breaked: 2}
	for s, op := range want {
		if s.Reported() != op || s.Initialized() != (s >= Ready) {
			t.Errorf("%s reported as %d", s, s.Reported())
		}
	}
}

func TestLogLinesCannotBeForged(t *testing.T) {
	var lines []string
	p := New(Options{Logf: func(l string) { lines = append(lines, l) }})
	p.Handle(&pc.SetPltfParamRequest{Key: "x\nserver started at port 1", Value: "\r\n"}, 1)
	for _, l := range lines {
		for _, r := range l {
			if r < 0x20 {
				t.Fatalf("a control character in the log line %q", l)
			}
		}
	}
	if len(lines) != 1 {
		t.Fatalf("%d lines", len(lines))
	}
}
