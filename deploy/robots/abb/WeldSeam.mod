MODULE WeldSeam
    ! weldseam text link, ABB (RAPID, ArcWare): capture, plan, weld.
    !
    ! The robot stands at the capture pose. main asks the daemon to trigger
    ! the camera and plan at the flange pose, fetches every waypoint line
    ! of every seam into arrays, checks each seam with CHECK (count and
    ! mean position, proto/ROBOTS.md), and only then moves: approach, the
    ! seam with ArcLStart, ArcL in zones at weld speed and ArcLEnd,
    ! retract; seam after seam. Nothing is read from the network while the
    ! arc burns. Needs the socket option (PC Interface or Socket Messaging,
    ! 616-1) and ArcWare.
    !
    ! The program asks for the daemon's process lines (HELLO,abb,PROCESS):
    ! with a weld procedure configured, each pass of a seam comes as a
    ! seam of its own and every weld waypoint with its travel speed and
    ! weave, which set wdWeld's weld_speed and wvWeld (ArcWare's weavedata:
    ! zigzag, one cycle per speed / frequency of seam, as wide as twice the
    ! half-swing) for the move into that waypoint. A speed of 0 (no
    ! procedure) welds at WELD_SPEED without weaving.
    !
    ! result is what the program branches on: 0 done; -code the daemon
    ! refused (its code; the cause is on the error line and shown);
    ! 1 no connection, 2 link lost, 3 no reply in time, 4 a reply not
    ! understood, 5 more lines than MAX_LINES, 6 a seam failed CHECK,
    ! 7 waypoint lines out of order, 8 another text link version. On any of
    ! them the torch has not left the capture pose.
    !
    ! A RAPID string holds 80 characters: every reply fits with its CR LF,
    ! and the plan line, longer with a joint set such as v_butt+lap, is
    ! sent in pieces. Waypoints are torch poses in the base frame: mm and a
    ! quaternion q1..q4.

    ! --- cell settings ---
    CONST string DAEMON_IP := "192.168.1.10";
    CONST num DAEMON_PORT := 7303;
    CONST string JOINT := "lap";
    CONST bool DRY_RUN := TRUE;
    CONST num WELD_SPEED := 8;
    CONST speeddata vWeld := [8, 50, 5000, 1000];
    CONST zonedata zWeld := [FALSE, 0.4, 0.4, 0.4, 0.04, 0.4, 0.04];
    CONST speeddata vApproach := [50, 200, 5000, 1000];
    CONST num REPLY_TIME := 30;
    CONST num MAX_LINES := 2000;
    CONST num CHECK_TOLERANCE := 0.1;
    ! The torch (TCP). The ArcWare seam and weld data, smWeld (seamdata)
    ! and wdWeld (welddata), are the cell's, declared with ArcWare's data;
    ! wdWeld's weld_speed is set before each move, from the waypoint's
    ! process line or WELD_SPEED; so is vSeam's speed in a dry run.
    PERS tooldata tWeldGun := [TRUE, [[0, 0, 350], [1, 0, 0, 0]], [3, [0, 0, 100], [1, 0, 0, 0], 0, 0, 0]];

    ! --- storage for a whole plan: a 1.5 m seam at 2 mm takes 753 lines ---
    ! A process line (kind 4) is stored at its own index, after its
    ! waypoint's, its speed and weave in speed, weaveAmp and weaveFreq.
    VAR robtarget path{MAX_LINES};
    VAR num kind{MAX_LINES};
    VAR num seamOf{MAX_LINES};
    VAR num speed{MAX_LINES};
    VAR num weaveAmp{MAX_LINES};
    VAR num weaveFreq{MAX_LINES};
    VAR bool process;
    VAR weavedata wvWeld;
    VAR speeddata vSeam;
    VAR num count;
    VAR num seamCount;
    VAR num result;
    VAR string reason;
    VAR socketdev sock;
    VAR num field{10};
    VAR num fields;
    VAR bool connected;

    PROC main()
        result := 0;
        reason := "";
        FetchPlan;
        SocketClose sock;
        IF result <> 0 THEN
            TPWrite "weldseam result " \Num:=result;
            TPWrite reason;
            Stop;
            RETURN;
        ENDIF
        Weld;
    ENDPROC

    ! Connects, plans and fetches; sets result. A lost link or a silent
    ! daemon raises a socket error, which the ERROR handler turns into a code.
    PROC FetchPlan()
        VAR robtarget capture;
        VAR string line;
        VAR num k;
        VAR num s;
        VAR num n;
        VAR num sx;
        VAR num sy;
        VAR num sz;

        connected := FALSE;
        SocketCreate sock;
        SocketConnect sock, DAEMON_IP, DAEMON_PORT \Time:=5;
        connected := TRUE;
        SocketSend sock \Str:="HELLO,abb,PROCESS\0D\0A";
        line := Receive();
        IF NOT Numbers(line) THEN
            RETURN;
        ENDIF
        IF field{2} <> 2 THEN
            result := 8;
            RETURN;
        ENDIF
        process := field{3} = 1;
        ! The flange pose, whatever the tool; the robot stands still.
        capture := CRobT(\Tool:=tool0 \WObj:=wobj0);
        SocketSend sock \Str:="TRIGGER," + JOINT + ",";
        SocketSend sock \Str:=NumToStr(capture.trans.x, 2) + "," + NumToStr(capture.trans.y, 2) + "," + NumToStr(capture.trans.z, 2) + ",";
        SocketSend sock \Str:=NumToStr(capture.rot.q1, 6) + "," + NumToStr(capture.rot.q2, 6) + ",";
        SocketSend sock \Str:=NumToStr(capture.rot.q3, 6) + "," + NumToStr(capture.rot.q4, 6) + "\0D\0A";
        line := Receive();
        IF NOT Numbers(line) THEN
            RETURN;
        ENDIF
        seamCount := field{2};
        count := field{3};
        IF count > MAX_LINES THEN
            result := 5;
            SocketSend sock \Str:="DROP\0D\0A";
            line := Receive();
            RETURN;
        ENDIF
        FOR k FROM 1 TO count DO
            SocketSend sock \Str:="NEXT\0D\0A";
            line := Receive();
            IF NOT Numbers(line) THEN
                RETURN;
            ENDIF
            IF (field{1} = 4 AND fields <> 6) OR (field{1} <> 4 AND fields <> 10) OR field{3} <> count - k THEN
                result := 7;
                RETURN;
            ENDIF
            IF k = 1 THEN
                IF field{1} <> 1 OR field{2} <> 1 THEN
                    result := 7;
                    RETURN;
                ENDIF
            ELSEIF field{1} = 1 THEN
                IF kind{k - 1} <> 3 OR field{2} <> seamOf{k - 1} + 1 THEN
                    result := 7;
                    RETURN;
                ENDIF
            ELSEIF (process AND kind{k - 1} = 2 AND field{1} <> 4) OR ((NOT process OR kind{k - 1} <> 2) AND field{1} = 4) THEN
                result := 7;
                RETURN;
            ELSEIF kind{k - 1} = 3 OR field{2} <> seamOf{k - 1} OR (field{1} = 3 AND kind{k - 1} <> 2 AND kind{k - 1} <> 4) THEN
                result := 7;
                RETURN;
            ENDIF
            path{k} := capture;
            kind{k} := field{1};
            seamOf{k} := field{2};
            IF field{1} = 4 THEN
                speed{k} := field{4};
                weaveAmp{k} := field{5};
                weaveFreq{k} := field{6};
            ELSE
                path{k}.trans := [field{4}, field{5}, field{6}];
                path{k}.rot := [field{7}, field{8}, field{9}, field{10}];
            ENDIF
        ENDFOR
        IF count > 0 THEN
            IF kind{count} <> 3 OR seamOf{count} <> seamCount THEN
                result := 7;
                RETURN;
            ENDIF
        ENDIF
        FOR s FROM 1 TO seamCount DO
            n := 0;
            sx := 0;
            sy := 0;
            sz := 0;
            FOR k FROM 1 TO count DO
                IF seamOf{k} = s AND kind{k} <> 4 THEN
                    n := n + 1;
                    sx := sx + path{k}.trans.x;
                    sy := sy + path{k}.trans.y;
                    sz := sz + path{k}.trans.z;
                ENDIF
            ENDFOR
            SocketSend sock \Str:="CHECK," + NumToStr(s, 0) + "\0D\0A";
            line := Receive();
            IF NOT Numbers(line) THEN
                RETURN;
            ENDIF
            IF fields <> 5 OR n = 0 OR field{2} <> n THEN
                result := 6;
                RETURN;
            ENDIF
            IF Abs(sx / n - field{3}) > CHECK_TOLERANCE OR Abs(sy / n - field{4}) > CHECK_TOLERANCE OR Abs(sz / n - field{5}) > CHECK_TOLERANCE THEN
                result := 6;
                RETURN;
            ENDIF
        ENDFOR
    ERROR
        IF NOT connected THEN
            result := 1;
        ELSEIF ERRNO = ERR_SOCK_TIMEOUT THEN
            result := 3;
        ELSEIF ERRNO = ERR_SOCK_CLOSED THEN
            result := 2;
        ELSE
            result := 4;
        ENDIF
        RETURN;
    ENDPROC

    ! One reply line, CR LF included: SocketReceive returns what has
    ! arrived, which may be part of the line.
    FUNC string Receive()
        VAR string line := "";
        VAR string part;

        WHILE StrFind(line, 1, "\0A") > StrLen(line) DO
            SocketReceive sock \Str:=part \Time:=REPLY_TIME;
            IF StrLen(line) + StrLen(part) > 80 THEN
                RETURN "";
            ENDIF
            line := line + part;
        ENDWHILE
        RETURN line;
    ENDFUNC

    ! Reads a reply's numbers into field{1..fields}. An error line sets
    ! result to its code and reason to its cause; a line not understood
    ! sets result to 4. FALSE unless the reply is a list of numbers
    ! leading with 0 or a waypoint's kind.
    FUNC bool Numbers(string line)
        VAR num start := 1;
        VAR num comma;
        VAR num stop;
        VAR string text;

        fields := 0;
        stop := StrFind(line, 1, "\0D\0A");
        IF stop > StrLen(line) THEN
            result := 4;
            RETURN FALSE;
        ENDIF
        WHILE start <= stop AND fields < 10 DO
            comma := StrFind(line, start, ",");
            IF comma > stop THEN
                comma := stop;
            ENDIF
            text := StrPart(line, start, comma - start);
            fields := fields + 1;
            IF NOT StrToVal(text, field{fields}) THEN
                result := 4;
                RETURN FALSE;
            ENDIF
            IF fields = 1 AND field{1} < 0 THEN
                result := field{1};
                reason := StrPart(line, comma + 1, stop - comma - 1);
                RETURN FALSE;
            ENDIF
            start := comma + 1;
        ENDWHILE
        IF start <= stop THEN
            result := 4;
            RETURN FALSE;
        ENDIF
        RETURN TRUE;
    ENDFUNC

    ! The whole plan is in memory; no network from here on.
    PROC Weld()
        VAR num i;
        VAR num after;

        ConfL \Off;
        FOR i FROM 1 TO count DO
            IF kind{i} = 4 THEN
                ! A process line: used with its waypoint, before it.
            ELSEIF kind{i} = 1 OR kind{i} = 3 THEN
                MoveL path{i}, vApproach, fine, tWeldGun \WObj:=wobj0;
            ELSEIF kind{i - 1} = 1 THEN
                ! ARC ON: ArcLStart strikes the arc at the seam's start.
                IF DRY_RUN THEN
                    MoveL path{i}, vApproach, fine, tWeldGun \WObj:=wobj0;
                ELSE
                    wdWeld.weld_speed := WELD_SPEED;
                    ArcLStart path{i}, vApproach, smWeld, wdWeld, fine, tWeldGun \WObj:=wobj0;
                ENDIF
            ELSE
                ! The pose line after waypoint i's, past its process line.
                after := i + 1;
                IF kind{i + 1} = 4 THEN
                    after := i + 2;
                ENDIF
                SetProcess i;
                IF kind{after} = 3 THEN
                    ! ARC OFF: ArcLEnd ends the arc at the seam's end.
                    IF DRY_RUN THEN
                        MoveL path{i}, vSeam, fine, tWeldGun \WObj:=wobj0;
                    ELSE
                        ArcLEnd path{i}, vSeam, smWeld, wdWeld \Weave:=wvWeld, fine, tWeldGun \WObj:=wobj0;
                    ENDIF
                ELSEIF DRY_RUN THEN
                    MoveL path{i}, vSeam, zWeld, tWeldGun \WObj:=wobj0;
                ELSE
                    ArcL path{i}, vSeam, smWeld, wdWeld \Weave:=wvWeld, zWeld, tWeldGun \WObj:=wobj0;
                ENDIF
            ENDIF
        ENDFOR
    ENDPROC

    ! The speed and weave of the move into weld waypoint i: its process
    ! line's, or WELD_SPEED and no weave where it has none or its speed
    ! is 0.
    PROC SetProcess(num i)
        vSeam := vWeld;
        wdWeld.weld_speed := WELD_SPEED;
        wvWeld.weave_shape := 0;
        IF kind{i + 1} = 4 THEN
            IF speed{i + 1} > 0 THEN
                wdWeld.weld_speed := speed{i + 1};
                vSeam.v_tcp := speed{i + 1};
                IF weaveAmp{i + 1} > 0 AND weaveFreq{i + 1} > 0 THEN
                    wvWeld.weave_shape := 1;
                    wvWeld.weave_type := 0;
                    wvWeld.weave_length := speed{i + 1} / weaveFreq{i + 1};
                    wvWeld.weave_width := 2 * weaveAmp{i + 1};
                ENDIF
            ENDIF
        ENDIF
    ENDPROC
ENDMODULE
