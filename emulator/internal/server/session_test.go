package server

// The sans-IO session: bytes in, reply frames out. Its fuzz invariant (as h11's): any input is handled request
// by request or closes the connection with a reason; nothing panics, every reply is a valid reply frame, and a
// closed session says nothing more. `go test` runs the seed corpus (every vector of fixtures/vectors plus
// preludes that bring the platform into Running); `go test -fuzz FuzzSession ./internal/server` explores.

import (
	"bytes"
	"testing"

	"pltf/emulator/internal/model"

	pc "platformctrl"
)

func newTestSession() (*Session, *model.Platform) {
	p := model.New(model.Options{})
	now := 0.0
	return NewSession(func(t pc.Telegram) model.Result {
		now += 0.25 // simulated time passes between requests, so moves advance
		return p.Handle(t, now)
	}), p
}

func frames(t testing.TB, ts ...pc.Telegram) []byte {
	var out []byte
	for _, x := range ts {
		f, err := pc.Encode(x)
		if err != nil {
			t.Fatal(err)
		}
		out = append(out, f...)
	}
	return out
}

// preludes bring the platform into the states where moves are taken.
func preludes(t testing.TB) [][]byte {
	up := []pc.Telegram{&pc.ConnectToPltfRequest{}, &pc.InitPltfRequest{}}
	var out [][]byte
	for _, mode := range []pc.MotionMode{pc.ModeMotionVel, pc.ModeMotionJoysoft, pc.ModeMotionAutomatic} {
		out = append(out, frames(t, append(up, &pc.SetModeRequest{Mode: mode}, &pc.StartRequest{})...))
	}
	return out
}

func checkStep(t *testing.T, st Step, closed bool) {
	if closed && len(st.Replies) > 0 {
		t.Fatalf("a closed session replied")
	}
	for _, r := range st.Replies {
		if _, err := pc.DecodeFrame(r, pc.Reply); err != nil {
			t.Fatalf("reply %x does not decode: %v", r, err)
		}
	}
}

func FuzzSession(f *testing.F) {
	var seeds [][]byte
	for _, file := range []string{"requests.json", "invalid.json"} {
		for _, v := range loadVectors(f, file) {
			if v.Direction == "request" {
				seeds = append(seeds, v.bytes(f))
			}
		}
	}
	for _, pre := range preludes(f) {
		f.Add(pre)
		for _, s := range seeds {
			f.Add(append(append([]byte{}, pre...), s...))
		}
	}
	for _, s := range seeds {
		f.Add(s)
	}
	f.Fuzz(func(t *testing.T, data []byte) {
		s, _ := newTestSession()
		closed := false
		// feed in pieces cut where the data says, so splits are explored too
		for len(data) > 0 {
			n := 1 + int(data[0])%7*len(data)/7
			if n > len(data) {
				n = len(data)
			}
			st := s.Feed(data[:n])
			checkStep(t, st, closed)
			closed = closed || st.Close
			data = data[n:]
		}
		st := s.End()
		checkStep(t, st, closed)
		if !st.Close {
			t.Fatal("the end of the stream did not close the session")
		}
	})
}

// TestSplitsChangeNothing: fed byte by byte or whole, the same requests give the same replies.
func TestSplitsChangeNothing(t *testing.T) {
	var all []byte
	for _, v := range loadVectors(t, "requests.json") {
		if v.ID != 16 && v.ID != 17 { // not EXIT, not CLOSE_SOCKET
			all = append(all, v.bytes(t)...)
		}
	}
	all = append(preludes(t)[2], all...)
	whole, _ := newTestSession()
	a := whole.Feed(all)
	bytewise, _ := newTestSession()
	var b [][]byte
	for i := range all {
		st := bytewise.Feed(all[i : i+1])
		if st.Close {
			t.Fatalf("closed at byte %d: %s", i, st.Problem)
		}
		b = append(b, st.Replies...)
	}
	if a.Close || len(a.Replies) != len(b) || len(b) < 10 {
		t.Fatalf("whole: %d replies (closed %v %s), bytewise: %d", len(a.Replies), a.Close, a.Problem, len(b))
	}
	for i := range b {
		if !bytes.Equal(a.Replies[i], b[i]) {
			t.Fatalf("reply %d differs", i)
		}
	}
}

func TestProblemsNameTheError(t *testing.T) {
	s, _ := newTestSession()
	st := s.Feed([]byte{0xff, 0x01, 0xfe, 0x02, 0, 0, 0, 1, 200}) // id 200 is no telegram
	if !st.Close || st.Problem == "" || !bytes.Contains([]byte(st.Problem), []byte("UnknownTelegram")) {
		t.Fatalf("%+v", st)
	}
	if again := s.Feed(frames(t, &pc.GetStatusRequest{})); !again.Close || len(again.Replies) > 0 {
		t.Fatal("a closed session answered")
	}
}
