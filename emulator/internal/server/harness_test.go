package server

// The test harness: the real network shell on 127.0.0.1 ephemeral ports, with a simulated clock that stands
// still between the test's own advances (no timed tests: where the platform is depends only on the clock).

import (
	"encoding/hex"
	"encoding/json"
	"errors"
	"io"
	"net"
	"os"
	"path/filepath"
	"strconv"
	"sync"
	"testing"
	"time"

	"pltf/emulator/internal/model"

	pc "platformctrl"
)

type manualClock struct {
	mu  sync.Mutex
	now float64
}

func (c *manualClock) Now() float64 { c.mu.Lock(); defer c.mu.Unlock(); return c.now }

func (c *manualClock) Advance(s float64) { c.mu.Lock(); c.now += s; c.mu.Unlock() }

type harness struct {
	t     *testing.T
	srv   *Server
	clock *manualClock
	ports []int
	done  chan struct{}
	logMu sync.Mutex
	log   []string
}

func startWith(t *testing.T, opts model.Options, tune func(*Server)) *harness {
	t.Helper()
	h := &harness{t: t, clock: &manualClock{}, done: make(chan struct{})}
	h.srv = &Server{Platform: model.New(opts), Clock: h.clock.Now, StallTimeout: 5 * time.Second,
		Logf: func(format string, args ...any) {
			h.logMu.Lock()
			h.log = append(h.log, format)
			h.logMu.Unlock()
		}}
	if tune != nil {
		tune(h.srv)
	}
	if err := h.srv.Listen("127.0.0.1", []int{0, 0}); err != nil {
		t.Fatal(err)
	}
	h.ports = h.srv.Ports()
	go func() { h.srv.Serve(); close(h.done) }()
	t.Cleanup(func() {
		h.srv.Shutdown()
		select {
		case <-h.done:
		case <-time.After(10 * time.Second):
			t.Error("the server did not stop")
		}
	})
	return h
}

func start(t *testing.T) *harness { return startWith(t, model.Options{}, nil) }

// conn is one client connection with a reply decoder.
type conn struct {
	t     *testing.T
	c     net.Conn
	dec   *pc.Decoder
	clock *manualClock
}

func (h *harness) dial(port int) *conn {
	h.t.Helper()
	c, err := net.DialTimeout("tcp", net.JoinHostPort("127.0.0.1", itoa(port)), 5*time.Second)
	if err != nil {
		h.t.Fatal(err)
	}
	h.t.Cleanup(func() { c.Close() })
	return &conn{t: h.t, c: c, dec: pc.NewDecoder(pc.Reply), clock: h.clock}
}

func itoa(n int) string { return strconv.Itoa(n) }

// write sends raw bytes.
func (c *conn) write(b []byte) {
	c.t.Helper()
	if _, err := c.c.Write(b); err != nil {
		c.t.Fatal(err)
	}
}

// send encodes and sends requests.
func (c *conn) send(ts ...pc.Telegram) {
	c.t.Helper()
	for _, t := range ts {
		frame, err := pc.Encode(t)
		if err != nil {
			c.t.Fatal(err)
		}
		c.write(frame)
	}
}

// readFrame reads one whole reply frame (raw bytes), within 5 s.
func (c *conn) readFrame() ([]byte, error) {
	_ = c.c.SetReadDeadline(time.Now().Add(5 * time.Second))
	head := make([]byte, 8)
	if _, err := io.ReadFull(c.c, head); err != nil {
		return nil, err
	}
	n := int(head[4])<<24 | int(head[5])<<16 | int(head[6])<<8 | int(head[7])
	if n > 1<<24 {
		return nil, errors.New("reply frame too large")
	}
	body := make([]byte, n)
	if _, err := io.ReadFull(c.c, body); err != nil {
		return nil, err
	}
	return append(head, body...), nil
}

// get sends a GET_* request and returns its decoded reply.
func (c *conn) get(t pc.Telegram) pc.Telegram {
	c.t.Helper()
	c.send(t)
	frame, err := c.readFrame()
	if err != nil {
		c.t.Fatalf("%s: no reply: %v", t.TelegramName(), err)
	}
	r, err := pc.DecodeFrame(frame, pc.Reply)
	if err != nil {
		c.t.Fatalf("%s: reply does not decode: %v", t.TelegramName(), err)
	}
	if r.TelegramID() != t.TelegramID() {
		c.t.Fatalf("%s: reply is %s", t.TelegramName(), r.TelegramName())
	}
	return r
}

// after lets s simulated seconds pass once the server has handled everything sent so far (a GET_POSITION
// round trip is the barrier).
func (c *conn) after(s float64) {
	c.t.Helper()
	c.position()
	c.clock.Advance(s)
}

func (c *conn) status() *pc.GetStatusReply { return c.get(&pc.GetStatusRequest{}).(*pc.GetStatusReply) }

func (c *conn) position() *pc.GetPositionReply {
	return c.get(&pc.GetPositionRequest{}).(*pc.GetPositionReply)
}

// closedByPeer is true when the server closed the connection (EOF or reset) within 5 s.
func (c *conn) closedByPeer() bool {
	_ = c.c.SetReadDeadline(time.Now().Add(5 * time.Second))
	buf := make([]byte, 1)
	for {
		_, err := c.c.Read(buf)
		if err == nil {
			continue
		}
		var ne net.Error
		return !(errors.As(err, &ne) && ne.Timeout())
	}
}

// vector is one entry of fixtures/vectors/*.json (the independent oracle).
type vector struct {
	Name      string          `json:"name"`
	Telegram  string          `json:"telegram"`
	ID        int             `json:"id"`
	Direction string          `json:"direction"`
	Hex       string          `json:"hex"`
	Fields    json.RawMessage `json:"fields"`
	Error     string          `json:"error"`
}

func (v vector) bytes(t testing.TB) []byte {
	b, err := hex.DecodeString(v.Hex)
	if err != nil {
		t.Fatal(err)
	}
	return b
}

func loadVectors(t testing.TB, file string) map[string]vector {
	t.Helper()
	raw, err := os.ReadFile(filepath.Join("..", "..", "..", "fixtures", "vectors", file))
	if err != nil {
		t.Fatal(err)
	}
	var list []vector
	if err := json.Unmarshal(raw, &list); err != nil {
		t.Fatal(err)
	}
	out := map[string]vector{}
	for _, v := range list {
		out[v.Name] = v
	}
	return out
}

func modelOptions() model.Options { return model.Options{} }
