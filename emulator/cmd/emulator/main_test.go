package main

import (
	"bytes"
	"io"
	"net"
	"os"
	"path/filepath"
	"regexp"
	"strconv"
	"strings"
	"sync"
	"syscall"
	"testing"
	"time"

	pc "platformctrl"
)

// syncBuffer collects the emulator's output while it runs.
type syncBuffer struct {
	mu sync.Mutex
	b  bytes.Buffer
}

func (s *syncBuffer) Write(p []byte) (int, error) {
	s.mu.Lock()
	defer s.mu.Unlock()
	return s.b.Write(p)
}
func (s *syncBuffer) String() string { s.mu.Lock(); defer s.mu.Unlock(); return s.b.String() }

// the launcher's pattern (harness/launch.py)
var started = regexp.MustCompile(`server started at port (\d+)`)

func launch(t *testing.T, args ...string) (ports []string, out *syncBuffer, stop chan os.Signal, code chan int) {
	t.Helper()
	out, stop, code = &syncBuffer{}, make(chan os.Signal, 1), make(chan int, 1)
	go func() { code <- run(args, out, io.Discard, stop) }()
	deadline := time.Now().Add(10 * time.Second)
	for time.Now().Before(deadline) {
		if m := started.FindAllStringSubmatch(out.String(), -1); len(m) == 2 {
			return []string{m[0][1], m[1][1]}, out, stop, code
		}
		time.Sleep(5 * time.Millisecond)
	}
	t.Fatalf("no two 'server started at port N' lines: %q", out.String())
	return
}

func request(t *testing.T, port string, req pc.Telegram) pc.Telegram {
	t.Helper()
	c, err := pc.Dial(net.JoinHostPort("127.0.0.1", port), 5*time.Second)
	if err != nil {
		t.Fatal(err)
	}
	defer c.Close()
	r, err := c.Request(req, req.TelegramID())
	if err != nil {
		t.Fatal(err)
	}
	return r
}

func TestStartsOnTwoPortsAndStopsOnSignal(t *testing.T) {
	ports, out, stop, code := launch(t, "--ports", "0,0", "--reply-delay-ms", "0", "--seed", "7")
	if ports[0] == ports[1] || !strings.Contains(out.String(), "emulator: server started at port "+ports[0]) {
		t.Fatalf("ports %v in %q", ports, out.String())
	}
	for _, port := range ports {
		if s := request(t, port, &pc.GetStatusRequest{}).(*pc.GetStatusReply); s.OperationState != pc.StOpNotInitialized {
			t.Fatalf("port %s: state %d", port, s.OperationState)
		}
	}
	stop <- syscall.SIGTERM
	select {
	case c := <-code:
		if c != 0 {
			t.Fatalf("exit status %d", c)
		}
	case <-time.After(10 * time.Second):
		t.Fatal("SIGTERM did not stop it")
	}
}

func TestDataDirGivesStartPoseAndDocuments(t *testing.T) {
	dir := t.TempDir()
	if err := os.MkdirAll(filepath.Join(dir, "Map"), 0o755); err != nil {
		t.Fatal(err)
	}
	start := "# a comment\n2000 10000 1.5\n"
	doc := `<?xml version="1.0"?><map Version="1.0"><layer/></map>`
	_ = os.WriteFile(filepath.Join(dir, "StartupPosition.dat"), []byte(start), 0o644)
	_ = os.WriteFile(filepath.Join(dir, "Map", "PltfMap.map"), []byte(doc), 0o644)
	ports, _, stop, code := launch(t, "--ports", "0,0", "--data-dir", dir, "--time-scale", "10")
	p := request(t, ports[0], &pc.GetPositionRequest{}).(*pc.GetPositionReply)
	if p.X != 2000 || p.Y != 10000 || p.Angle != 1.5 {
		t.Fatalf("start pose %+v", p)
	}
	m := request(t, ports[1], &pc.GetMapRequest{}).(*pc.GetMapReply)
	if m.XML != doc || m.Name != "PltfMap.map" { // E-SRV-011: loaded at start-up under the file name
		t.Fatalf("map %q %q", m.XML, m.Name)
	}
	// CMD_SAVE_ROADMAP writes into the data dir (E-CMD-008)
	c, _ := pc.Dial(net.JoinHostPort("127.0.0.1", ports[0]), 5*time.Second)
	rm := `<roadmap><stations/><edges/></roadmap>`
	_ = c.SetRoadmap("x.rm", rm)
	_ = c.SaveRoadmap()
	_, _ = c.GetRoadmap() // a round trip: both commands are handled
	c.Close()
	if b, _ := os.ReadFile(filepath.Join(dir, "Roadmap", "PltfRoadmap.rm")); string(b) != rm {
		t.Fatalf("saved %q", b)
	}
	stop <- syscall.SIGINT
	<-code
}

func TestBadArgumentsAreOneLine(t *testing.T) {
	for _, args := range [][]string{
		{"--ports", "10000"}, {"--ports", "a,b"}, {"--ports", "1,70000"}, {"--reply-delay-ms", "-1"},
		{"--time-scale", "0"}, {"extra"}, {"--no-such-flag"},
	} {
		var errOut bytes.Buffer
		if code := run(args, io.Discard, &errOut, nil); code != 2 {
			t.Errorf("%v: exit %d", args, code)
		}
		if msg := errOut.String(); !strings.HasPrefix(msg, "emulator: ") || strings.Count(msg, "\n") != 1 {
			t.Errorf("%v: %q", args, errOut.String())
		}
	}
	// a busy port is a one-line error too
	ln, _ := net.Listen("tcp", "127.0.0.1:0")
	defer ln.Close()
	port := ln.Addr().(*net.TCPAddr).Port
	var errOut bytes.Buffer
	if code := run([]string{"--ports", "0," + strconv.Itoa(port)}, io.Discard, &errOut, nil); code != 2 ||
		!strings.Contains(errOut.String(), "cannot listen") {
		t.Fatalf("busy port: %d %q", code, errOut.String())
	}
}
