// Package server is the emulator's network side: the sans-IO Session (bytes in, reply frames out) and the TCP
// listeners that own the sockets and the clock.
package server

import (
	"fmt"

	"pltf/emulator/internal/model"

	pc "platformctrl"
)

// Step is what a Session did with the bytes it was fed.
type Step struct {
	Replies [][]byte // whole reply frames, in order (guide 6.2 framing, E-WIRE-001)
	Close   bool     // the connection ends here (CMD_CLOSE_SOCKET, a malformed frame, or the end of the stream)
	Exit    bool     // CMD_EXIT: the emulator ends
	Problem string   // why a malformed stream closed the connection (E-WIRE-006), for the log
}

// Handler takes one decoded request; the server's wraps the platform with its lock and clock.
type Handler func(pc.Telegram) model.Result

// Session is one client connection, without the socket.
//
// Rules (E-WIRE-006, E-WIRE-004, E-CMD-013): requests are decoded with the generated codec, strictly - a bad
// header, a length over 16 MiB, an unknown identifier, a field out of range, a telegram too short or too long
// all close the connection, and nothing after them is handled; every complete request before them is. Only
// GET_* produce a reply. A closed session ignores further input.
type Session struct {
	dec    *pc.Decoder
	handle Handler
	closed bool
}

// NewSession decodes requests and passes them to handle.
func NewSession(handle Handler) *Session {
	return &Session{dec: pc.NewDecoder(pc.Request), handle: handle}
}

// Pending is the number of bytes of a frame not yet complete (the stall timeout watches it, E-SRV-014).
func (s *Session) Pending() int { return s.dec.Pending() }

// Feed takes received bytes.
func (s *Session) Feed(data []byte) Step {
	if s.closed {
		return Step{Close: true}
	}
	s.dec.Feed(data)
	return s.drain()
}

// End takes the end of the stream: complete requests are still handled; then the connection closes.
func (s *Session) End() Step {
	if s.closed {
		return Step{Close: true}
	}
	s.dec.End()
	st := s.drain()
	s.closed, st.Close = true, true
	return st
}

func (s *Session) drain() Step {
	var st Step
	for {
		t, err := s.dec.Next()
		if err != nil {
			s.closed, st.Close, st.Problem = true, true, err.Error()
			return st
		}
		if t == nil {
			return st
		}
		res := s.handle(t)
		if res.Reply != nil {
			frame, err := pc.Encode(res.Reply)
			if err != nil { // our own fault: never send a broken frame (cannot happen with held INT ranges)
				st.Problem = fmt.Sprintf("reply %s not encodable: %v", res.Reply.TelegramName(), err)
			} else {
				st.Replies = append(st.Replies, frame)
			}
		}
		if res.Close || res.Exit {
			s.closed, st.Close, st.Exit = true, true, res.Exit
			return st
		}
	}
}
