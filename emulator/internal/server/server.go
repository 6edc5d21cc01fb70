package server

// The TCP side (guide 6.1: "listens for clients on the socket ports 10000 and 10002. For each port one client is
// able to connect to the platform").
//
// Rules:
//   - One client per port at a time: the next connection is accepted only after the current one has closed, so
//     a second client waits in the listen backlog until then (E-WIRE-007 alternative reading; the reference
//     server accepts and closes it at once).
//   - Each reply is written ReplyDelay after its request was handled (slower replies than the reference server).
//   - A partial frame that stalls for StallTimeout closes the connection (E-SRV-014); an idle connection never
//     times out.
//   - Requests of both ports go to one platform under one lock, at the simulated time of the Clock.
//   - Nothing a peer sends stops the server: a malformed stream closes its connection (E-WIRE-006); only
//     CMD_EXIT (E-SRV-015) or Shutdown ends it.

import (
	"errors"
	"fmt"
	"net"
	"strconv"
	"sync"
	"time"

	"pltf/emulator/internal/model"

	pc "platformctrl"
)

// Server runs the platform on its listeners.
type Server struct {
	Platform     *model.Platform
	Clock        func() float64 // simulated seconds since start
	ReplyDelay   time.Duration
	StallTimeout time.Duration
	Logf         func(format string, args ...any)

	mu        sync.Mutex // the platform
	connMu    sync.Mutex
	listeners []net.Listener
	conns     map[net.Conn]bool
	done      chan struct{}
	once      sync.Once
	wg        sync.WaitGroup
}

// Listen opens one listener per port on host (port 0: an ephemeral port) and logs "server started at port N"
// for each, in port order (the line every launcher of the toolkit reads).
func (s *Server) Listen(host string, ports []int) error {
	s.done = make(chan struct{})
	s.conns = map[net.Conn]bool{}
	for _, port := range ports {
		ln, err := net.Listen("tcp", net.JoinHostPort(host, strconv.Itoa(port)))
		if err != nil {
			s.closeListeners()
			return fmt.Errorf("cannot listen on %s port %d: %w", host, port, err)
		}
		s.listeners = append(s.listeners, ln)
	}
	for _, ln := range s.listeners {
		s.logf("emulator: server started at port %d", ln.Addr().(*net.TCPAddr).Port)
	}
	return nil
}

// Ports are the bound ports, in order.
func (s *Server) Ports() []int {
	out := make([]int, len(s.listeners))
	for i, ln := range s.listeners {
		out[i] = ln.Addr().(*net.TCPAddr).Port
	}
	return out
}

// Serve accepts clients on every listener until Shutdown or CMD_EXIT; it returns when all have stopped.
func (s *Server) Serve() {
	for _, ln := range s.listeners {
		s.wg.Add(1)
		go s.acceptLoop(ln)
	}
	s.wg.Wait()
}

// Done is closed when the server stops.
func (s *Server) Done() <-chan struct{} { return s.done }

// Shutdown closes the listeners and every connection.
func (s *Server) Shutdown() {
	s.once.Do(func() {
		close(s.done)
		s.closeListeners()
		s.connMu.Lock()
		for c := range s.conns {
			c.Close()
		}
		s.connMu.Unlock()
	})
}

func (s *Server) closeListeners() {
	for _, ln := range s.listeners {
		ln.Close()
	}
}

func (s *Server) logf(format string, args ...any) {
	if s.Logf != nil {
		s.Logf(format, args...)
	}
}

func (s *Server) acceptLoop(ln net.Listener) {
	defer s.wg.Done()
	port := ln.Addr().(*net.TCPAddr).Port
	for {
		conn, err := ln.Accept()
		if err != nil {
			select {
			case <-s.done:
				return
			default:
			}
			var ne net.Error
			if errors.As(err, &ne) && ne.Timeout() {
				continue
			}
			s.logf("port %d: accept failed: %v", port, err)
			time.Sleep(10 * time.Millisecond) // e.g. out of file descriptors: try again, never spin
			continue
		}
		s.serveConn(port, conn) // one client at a time: the next waits in the backlog (E-WIRE-007 alternative)
	}
}

func (s *Server) track(c net.Conn, on bool) bool {
	s.connMu.Lock()
	defer s.connMu.Unlock()
	select {
	case <-s.done:
		return false
	default:
	}
	if on {
		s.conns[c] = true
	} else {
		delete(s.conns, c)
	}
	return true
}

func (s *Server) handle(t pc.Telegram) model.Result {
	s.mu.Lock()
	defer s.mu.Unlock()
	return s.Platform.Handle(t, s.Clock())
}

func (s *Server) serveConn(port int, conn net.Conn) {
	defer conn.Close()
	if !s.track(conn, true) {
		return
	}
	defer s.track(conn, false)
	peer := conn.RemoteAddr().String()
	s.logf("port %d: client %s connected", port, peer)
	sess := NewSession(s.handle)
	buf := make([]byte, 1<<16)
	for {
		deadline := time.Time{}
		if sess.Pending() > 0 && s.StallTimeout > 0 {
			deadline = time.Now().Add(s.StallTimeout)
		}
		_ = conn.SetReadDeadline(deadline)
		n, err := conn.Read(buf)
		var st Step
		if n > 0 {
			st = sess.Feed(buf[:n])
		}
		if err != nil && !st.Close {
			var ne net.Error
			if errors.As(err, &ne) && ne.Timeout() {
				s.logf("port %d: client %s: partial frame stalled for %s, closed (E-SRV-014)", port, peer, s.StallTimeout)
				return
			}
			more := sess.End()
			st.Replies, st.Close, st.Exit, st.Problem = append(st.Replies, more.Replies...), true, more.Exit, more.Problem
		}
		for _, r := range st.Replies {
			if s.ReplyDelay > 0 {
				time.Sleep(s.ReplyDelay)
			}
			_ = conn.SetWriteDeadline(time.Now().Add(30 * time.Second))
			if _, werr := conn.Write(r); werr != nil {
				s.logf("port %d: client %s: write failed: %v", port, peer, werr)
				break
			}
		}
		if st.Problem != "" {
			s.logf("port %d: client %s: %s, connection closed (E-WIRE-006)", port, peer, st.Problem)
		}
		if st.Exit {
			s.logf("CMD_EXIT: the emulator stops")
			s.Shutdown()
			return
		}
		if st.Close {
			s.logf("port %d: client %s closed", port, peer)
			return
		}
	}
}
